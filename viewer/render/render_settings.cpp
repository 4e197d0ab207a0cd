#include "viewer/render/render_settings.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "viewer/render/scene_groups.h"

namespace vxl {

namespace {
// Unsorted draws in the files' streamline order, not by voxel: its plan only culls (Any).
constexpr RenderModeInfo kModes[] = {
    {RenderMode::Opaque, "opaque", "depth-tested, no blending", false, PlanOrder::Any, false},
    {RenderMode::Unsorted, "unsorted", "blended in dataset (streamline) order, like TrackVis", false, PlanOrder::Any,
     false},
    {RenderMode::Additive, "additive",
     "MRtrix-like: a depth-tested opaque pass and an additive pass, mixed by the opacity", false, PlanOrder::Any,
     false},
    {RenderMode::Wboit, "wboit", "weighted blended order-independent transparency (McGuire & Bavoil 2013)", false,
     PlanOrder::Any, false},
    {RenderMode::Basic, "basic", "voxels sorted back to front, segments in dataset order inside each voxel", false,
     PlanOrder::Block, true},
    {RenderMode::Axis, "axis", "voxels sorted back to front, each drawn in its nearest precomputed order (Voxlines)",
     false, PlanOrder::Nearest, true},
    {RenderMode::Segsort, "segsort",
     "voxels sorted as axis, each voxel's segments sorted for the exact view on the CPU every frame: slow, a "
     "reference for the orders",
     false, PlanOrder::Block, false},
    {RenderMode::Exact, "exact", "per-fragment sorted reference (needs OpenGL 4.3)", true, PlanOrder::Visibility,
     false},
};
struct ColorName {
  ColorMode mode;
  const char* name;
};
constexpr ColorName kColors[] = {{ColorMode::Direction, "direction"},
                                 {ColorMode::Fixed, "fixed"},
                                 {ColorMode::Scalar, "scalar"},
                                 {ColorMode::Group, "group"}};
}  // namespace

std::optional<ColorMode> parse_color_mode(const std::string& name) {
  for (const ColorName& c : kColors)
    if (name == c.name) return c.mode;
  return std::nullopt;
}

const char* color_mode_name(ColorMode mode) {
  for (const ColorName& c : kColors)
    if (c.mode == mode) return c.name;
  return "?";
}

std::vector<std::string> color_mode_names() {
  std::vector<std::string> names;
  for (const ColorName& c : kColors) names.emplace_back(c.name);
  return names;
}

std::optional<glm::vec3> parse_hex_color(const std::string& text) {
  if (text.size() != 7 || text[0] != '#') return std::nullopt;
  glm::vec3 c;
  for (int i = 0; i < 3; ++i) {
    int v = 0;
    for (int k = 0; k < 2; ++k) {
      const char ch = static_cast<char>(std::tolower(static_cast<unsigned char>(text[1 + 2 * i + k])));
      if (ch >= '0' && ch <= '9')
        v = 16 * v + (ch - '0');
      else if (ch >= 'a' && ch <= 'f')
        v = 16 * v + (ch - 'a' + 10);
      else
        return std::nullopt;
    }
    c[i] = v / 255.0f;
  }
  return c;
}

std::string hex_color(const glm::vec3& c) {
  char buf[8];
  auto byte = [](float v) { return static_cast<int>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", byte(c.r), byte(c.g), byte(c.b));
  return buf;
}

std::optional<GroupStyle> parse_group_style(const std::string& text) {
  const std::size_t eq = text.rfind('=');
  if (eq == std::string::npos || eq == 0) return std::nullopt;
  GroupStyle g;
  g.name = text.substr(0, eq);
  std::string spec = text.substr(eq + 1);
  const std::size_t colon = spec.find(':');
  const std::string colour = spec.substr(0, colon);
  if (!colour.empty()) {
    g.color = parse_hex_color(colour);
    if (!g.color) return std::nullopt;
  }
  if (colon != std::string::npos) {
    const std::string o = spec.substr(colon + 1);
    char* end = nullptr;
    g.opacity = std::strtof(o.c_str(), &end);
    if (o.empty() || *end != '\0' || !(g.opacity >= 0.0f && g.opacity <= 1.0f)) return std::nullopt;
  } else if (colour.empty()) {
    return std::nullopt;  // "NAME=" says nothing
  }
  return g;
}

glm::vec4 RenderSettings::group_color(const std::string& name, std::size_t index) const {
  for (const GroupStyle& g : group_styles)
    if (g.name == name) return glm::vec4(g.color.value_or(group_palette(index)), g.opacity);
  return glm::vec4(group_palette(index), 1.0f);
}

const GroupStyle* RenderSettings::find_style(const std::string& name) const {
  for (const GroupStyle& g : group_styles)
    if (g.name == name) return &g;
  return nullptr;
}

GroupStyle& RenderSettings::style_of(const std::string& name) {
  for (GroupStyle& g : group_styles)
    if (g.name == name) return g;
  group_styles.push_back({name, std::nullopt, 1.0f});
  return group_styles.back();
}

std::span<const RenderModeInfo> render_modes() { return kModes; }

const RenderModeInfo& render_mode_info(RenderMode mode) { return kModes[static_cast<std::size_t>(mode)]; }

std::vector<std::string> render_mode_names() {
  std::vector<std::string> names;
  for (const RenderModeInfo& m : kModes) names.emplace_back(m.name);
  return names;
}

std::optional<RenderMode> parse_render_mode(const std::string& name) {
  for (const RenderModeInfo& m : kModes)
    if (name == m.name) return m.mode;
  return std::nullopt;
}

const char* render_mode_name(RenderMode mode) {
  for (const RenderModeInfo& m : kModes)
    if (m.mode == mode) return m.name;
  return "?";
}

}  // namespace vxl
