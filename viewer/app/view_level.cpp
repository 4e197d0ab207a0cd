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

std::optional<FocusFirstLevels> focus_first_levels(LevelLayouts& context, const SceneLayout& focus,
                                                   const SceneDetail& detail, const LayoutBytes& bytes) {
  if (detail.forced) return std::nullopt;
  const std::uint64_t focus_bytes = bytes(focus);
  if (focus_bytes > detail.budget) return std::nullopt;
  for (std::uint32_t level = 0; level <= context.coarsest(); ++level)
    if (bytes(context.at(level)) <= detail.budget - focus_bytes) return FocusFirstLevels{level, focus_bytes};
  return std::nullopt;
}

LayoutBytes visible_bytes(const Camera& camera, double aspect, const SceneBounds& bounds, const Clipping& clipping) {
  return [=](const SceneLayout& layout) { return view_bytes(layout, camera, aspect, bounds, clipping); };
}

}  // namespace vxl::app
