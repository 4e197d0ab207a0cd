#include "viewer/app/view_level.h"

namespace vxl::app {

const SceneLayout& LevelLayouts::at(std::uint32_t level) {
  std::unique_ptr<SceneLayout>& layout = layouts_[level];
  if (!layout) layout = std::make_unique<SceneLayout>(files_, span_texels_, level);
  return *layout;
}

std::uint32_t level_for_view(LevelLayouts& layouts, const SceneDetail& detail, const Camera& camera, double aspect,
                             const SceneBounds& bounds, const Clipping& clipping) {
  if (detail.forced) return detail.level;
  for (std::uint32_t level = 0; level < detail.level; ++level)
    if (view_bytes(layouts.at(level), camera, aspect, bounds, clipping) <= detail.budget) return level;
  return detail.level;
}

}  // namespace vxl::app
