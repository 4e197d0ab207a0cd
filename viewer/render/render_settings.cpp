#include "render_settings.h"

namespace vxl {

namespace {
struct ModeName {
  RenderMode mode;
  const char* name;
};
constexpr ModeName kModes[] = {{RenderMode::Opaque, "opaque"}, {RenderMode::Unsorted, "unsorted"},
                               {RenderMode::Additive, "additive"}, {RenderMode::Wboit, "wboit"},
                               {RenderMode::Basic, "basic"}, {RenderMode::Axis, "axis"},
                               {RenderMode::Exact, "exact"}};
}  // namespace

std::optional<RenderMode> parse_render_mode(const std::string& name) {
  for (const ModeName& m : kModes)
    if (name == m.name) return m.mode;
  return std::nullopt;
}

const char* render_mode_name(RenderMode mode) {
  for (const ModeName& m : kModes)
    if (m.mode == mode) return m.name;
  return "?";
}

}  // namespace vxl
