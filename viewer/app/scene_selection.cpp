#include "viewer/app/scene_selection.h"

#include <cstdio>

#include "converter/selection/streamline_selection.h"

namespace vxl::app {

std::optional<SceneGroups> select_in_scene(std::span<const VxlFile* const> files, const ViewerOptions& o) {
  if (!o.selecting()) return std::nullopt;
  SelectionCriteria criteria;
  for (const std::string& r : o.include) criteria.include.push_back(parse_region(r));
  for (const std::string& r : o.exclude) criteria.exclude.push_back(parse_region(r));
  for (const std::string& r : o.ends_in) criteria.ends_in.push_back(parse_region(r));
  std::vector<std::vector<std::uint64_t>> kept;
  std::uint64_t selected = 0, total = 0;
  for (const VxlFile* f : files) {
    kept.push_back(select_streamlines(*f, criteria).streamlines);
    selected += kept.back().size();
    total += f->meta().streamline_count;
  }
  std::fprintf(stderr, "voxview: %llu of %llu streamlines selected (the focus; the others are context)\n",
               (unsigned long long)selected, (unsigned long long)total);
  return SceneGroups::selection(files, kept);
}

}  // namespace vxl::app
