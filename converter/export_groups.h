// The groups of a .vxl (GRPS) in exports to formats without groups (TCK, VTK): one group's streamlines as
// a subset, one TCK per group, file names made from group names, and the warnings when groups or their rows
// of values (TRX dpg) are lost.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "converter/export_tck.h"
#include "converter/streamline_subset.h"
#include "format/vxl_file.h"

namespace vxl {

// The streamlines of group `name`. Throws vxl::Error (Usage) when the file has no such group, naming those
// it has.
StreamlineSubset group_subset(const VxlFile& file, const std::string& name);

// "N group(s) not written: FORMAT has no place for them: 'A' (n streamlines), ..." when the file has
// groups with members among the written streamlines (`subset`, or all); nothing otherwise.
std::optional<std::string> groups_not_written(const VxlFile& file, const std::string& format,
                                              const StreamlineSubset* subset = nullptr);

// "N row(s) of values per group (TRX dpg) not written: FORMAT has no place for them: 'GROUP/NAME', ..." when
// the file has such rows (GDAT; only group `only_group`'s when given); nothing otherwise.
std::optional<std::string> group_values_not_written(const VxlFile& file, const std::string& format,
                                                    const std::optional<std::string>& only_group = std::nullopt);

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
