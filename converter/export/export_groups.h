// A .vxl's groups (GRPS) exported one file each: one TCK per group (`voxlines export --split-groups DIR`),
// with file names made from the group names.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "converter/export/export_tck.h"
#include "converter/export/streamline_subset.h"
#include "format/vxl_file.h"

namespace vxl {

// One file name per group (same order), without the extension: the group name with '/', '\', control
// characters and a leading '.' replaced by '_' (never empty), cut to kMaxGroupFileNameBytes at a UTF-8
// character's start (a file system holds 255 bytes a name, with the extension and the suffix), made unique,
// ignoring case, by "_2", "_3", …
inline constexpr std::size_t kMaxGroupFileNameBytes = 200;
std::vector<std::string> group_file_names(const std::vector<StreamlineGroup>& groups);

struct SplitGroupFile {
  std::string group, tck, tsf;  // tsf empty when none was written
  ExportSummary summary;
};

// Writes DIR/NAME.tck for every group (and DIR/NAME.tsf beside each when `value` names a per-point set),
// creating DIR when its parent exists. Each file is written atomically. Throws vxl::Error: Usage when the
// file has no groups or no per-point set `value`; Output when DIR cannot be made or written.
std::vector<SplitGroupFile> export_tck_per_group(const VxlFile& file, const std::string& dir,
                                                 const std::optional<std::string>& value);

}  // namespace vxl
