// The warnings of an export to a format without groups (TCK, TRK, VTK) when the .vxl's groups (GRPS) or their
// rows of values (TRX dpg, GDAT) are lost.
#pragma once

#include <optional>
#include <string>

#include "converter/export/streamline_subset.h"
#include "format/vxl_file.h"

namespace vxl {

// "N group(s) not written: FORMAT has no place for them: 'A' (n streamlines), ..." when the file has
// groups with members among the written streamlines (`subset`, or all); nothing otherwise.
std::optional<std::string> groups_not_written(const VxlFile& file, const std::string& format,
                                              const StreamlineSubset* subset = nullptr);

// "N row(s) of values per group (TRX dpg) not written: FORMAT has no place for them: 'GROUP/NAME', ..." when
// the file has such rows (GDAT; only group `only_group`'s when given); nothing otherwise.
std::optional<std::string> group_values_not_written(const VxlFile& file, const std::string& format,
                                                    const std::optional<std::string>& only_group = std::nullopt);

}  // namespace vxl
