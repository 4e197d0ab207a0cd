// What the user chooses about a picture: transparency mode, colouring, lighting, opacity, line width,
// background, slab and clip planes, anatomical slices.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "viewer/render/clip_planes.h"
#include "viewer/render/colormap.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/region_shapes.h"

namespace vxl {

// Transparency modes (docs/rendering.md). All draw the same data from the same camera; render_modes()
// names and describes them.
enum class RenderMode { Opaque, Unsorted, Additive, Wboit, Basic, Axis, Segsort, Exact };

// The one list of the modes, in the order the panel shows them and M cycles through them: --mode, saved
// views, the panel and the help all read it.
// Each mode's facts live here, so that the window, the refinement at rest and the panel read them rather
// than keep their own lists.
struct RenderModeInfo {
  RenderMode mode;
  const char* name;         // as --mode and saved views spell it
  const char* description;  // one line
  bool needs_gl43;          // runs only where the context has OpenGL 4.3 (elsewhere the window shows axis)
  PlanOrder plan_order;     // how the frame plan orders the visible voxels (frame_plan.h); its pass plans so
  // The exact mode is this mode's reference: at rest the window goes on to the exact picture ("exact when
  // still", rest_refinement.h).
  bool refines_to_exact;
};
std::span<const RenderModeInfo> render_modes();
// The table's entry of `mode`.
const RenderModeInfo& render_mode_info(RenderMode mode);
std::vector<std::string> render_mode_names();

std::optional<RenderMode> parse_render_mode(const std::string& name);
const char* render_mode_name(RenderMode mode);

enum class ColorMode {
  Direction,  // |p1 - p0| as RGB, the convention of every tractography viewer
  Fixed,      // one colour
  Scalar,     // a value set of the file (per point or per streamline) through a colour map
  Group,      // one colour per group (scene_groups.h)
};
std::optional<ColorMode> parse_color_mode(const std::string& name);
const char* color_mode_name(ColorMode mode);
// Every colour mode's name, in the table's order ("direction", "fixed", "scalar", "group"), for help texts.
std::vector<std::string> color_mode_names();

// What the user changed about one group: its colour (else the palette's) and its opacity, a factor on
// RenderSettings::opacity (0 hides the group).
struct GroupStyle {
  std::string name;
  std::optional<glm::vec3> color;
  float opacity = 1.0f;
  bool operator==(const GroupStyle&) const = default;
};

// "#RRGGBB" -> colour in [0, 1].
std::optional<glm::vec3> parse_hex_color(const std::string& text);
std::string hex_color(const glm::vec3& color);
// "NAME=#RRGGBB", "NAME=#RRGGBB:0.5", "NAME=:0" (opacity only); nullopt when malformed.
std::optional<GroupStyle> parse_group_style(const std::string& text);

// The anatomical image's slices (slice_renderer.h): which planes through the focus point (the camera's
// target) are shown, and the grey range.
struct SliceSettings {
  bool axial = true, coronal = true, sagittal = true;
  // The plane through the focus perpendicular to the view: with a slab, the slice in its middle.
  bool view_plane = false;
  std::optional<std::array<float, 2>> range;  // values shown black and white; none: the image's default window
  bool any() const { return axial || coronal || sagittal || view_plane; }
  bool operator==(const SliceSettings&) const = default;
};

// The line opacity voxview and the web viewer open with.
inline constexpr float kDefaultLineOpacity = 0.3f;

struct RenderSettings {
  RenderMode mode = RenderMode::Axis;
  ColorMode color = ColorMode::Direction;
  glm::vec3 fixed_color{1.0f, 0.85f, 0.3f};
  float opacity = 0.5f;              // 1 down to 0.001
  float line_width = 1.0f;           // pixels
  glm::vec3 background_color{0.0f};  // background_color.h parses and names it
  // `axis` mode: keep a voxel's order until another stored order is closer to its view direction by
  // more than this cosine margin (FramePlan::order_hysteresis). 0: off, the paper's rule every frame.
  float order_hysteresis = 0.0f;
  Colormap colormap = Colormap::Viridis;      // for ColorMode::Scalar
  std::string scalar;                         // the value set to colour by; empty: the first the scene has
  std::optional<std::array<float, 2>> range;  // values mapped to the colour map's ends; none: the set's min, max
  std::vector<GroupStyle> group_styles;       // only the groups the user changed
  Clipping clipping;                          // slab and clip planes (clip_planes.h)
  bool lighting = false;                      // illuminated lines (line_lighting.h)
  SliceSettings slices;                       // drawn when the renderer has a volume (Renderer::set_volume)
  // The selection's regions drawn as translucent shells around the lines (region_shells.h); empty: none.
  std::vector<RegionShape> regions;
  // Drawn over the picture (picture_annotations.h), not by the renderer: L/R, A/P, S/I at the picture's
  // edges and an axes triad; with ColorMode::Scalar, a colour bar with the range and the value set's name.
  bool orientation_labels = false;
  bool colorbar = false;
  glm::vec3 background() const { return background_color; }
  // The colour and opacity factor of group `index` called `name`.
  glm::vec4 group_color(const std::string& name, std::size_t index) const;
  GroupStyle& style_of(const std::string& name);                // the user's entry for `name`, added when missing
  const GroupStyle* find_style(const std::string& name) const;  // the user's entry for `name`, if any
  // Whether two settings draw the same picture (the window refines a picture until they change).
  bool operator==(const RenderSettings&) const = default;
};

}  // namespace vxl
