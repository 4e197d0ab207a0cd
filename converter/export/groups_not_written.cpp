#include "converter/export/groups_not_written.h"

namespace vxl {

std::optional<std::string> groups_not_written(const VxlFile& file, const std::string& format,
                                              const StreamlineSubset* subset) {
  std::string lost;
  std::size_t count = 0;
  for (const StreamlineGroup& g : file.groups()) {
    const std::uint64_t members = subset ? subset->renumber(g.members).size() : g.members.size();
    if (members == 0) continue;
    lost += (count++ ? ", '" : "'") + g.name + "' (" + std::to_string(members) + " streamlines)";
  }
  if (count == 0) return std::nullopt;
  // Some of the streamlines (a selection, or one group) are written to one file: only .trx keeps their groups.
  const char* advice = subset
                           ? " (write them to .trx to keep their groups)"
                           : " (export to .trx, or write one group with --group NAME or each with --split-groups DIR)";
  return std::to_string(count) + " group(s) not written: " + format + " has no place for them: " + lost + advice;
}

std::optional<std::string> group_values_not_written(const VxlFile& file, const std::string& format,
                                                    const std::optional<std::string>& only_group) {
  if (file.group_values().empty()) return std::nullopt;
  const std::vector<StreamlineGroup> groups = file.groups();
  std::string lost;
  std::size_t count = 0;
  for (const GroupValues& v : file.group_values()) {
    if (only_group && groups[v.group].name != *only_group) continue;
    lost += (count++ ? ", '" : "'") + groups[v.group].name + "/" + v.name + "'";
  }
  if (count == 0) return std::nullopt;
  return std::to_string(count) + " row(s) of values per group (TRX dpg) not written: " + format +
         " has no place for them: " + lost + " (export to .trx)";
}

}  // namespace vxl
