// What the user chooses about a picture: transparency mode, colouring, lighting, opacity, line width,
// background, slab and clip planes.
#pragma once

#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "clip_planes.h"

namespace vxl {

// Transparency modes (BRIEF §6). All draw the same data from the same camera.
enum class RenderMode {
  Opaque,    // depth-tested, no blending
  Unsorted,  // blended in dataset (streamline) order, like TrackVis
  Additive,  // MRtrix-like: a depth-tested opaque pass and an additive pass, mixed by the opacity
  Wboit,     // weighted blended order-independent transparency (McGuire & Bavoil 2013)
  Basic,     // voxels sorted back to front, segments in dataset order inside each voxel
  Axis,      // voxels sorted back to front + the nearest precomputed order per voxel (the product)
  Exact,     // per-fragment sorted reference (needs OpenGL >= 4.3)
};

std::optional<RenderMode> parse_render_mode(const std::string& name);
const char* render_mode_name(RenderMode mode);

enum class ColorMode { Direction, Fixed };

struct RenderSettings {
  RenderMode mode = RenderMode::Axis;
  ColorMode color = ColorMode::Direction;
  glm::vec3 fixed_color{1.0f, 0.85f, 0.3f};
  float opacity = 0.5f;    // 1 down to 0.001
  float line_width = 1.0f; // pixels
  bool white_background = false;
  // `axis` mode: keep a voxel's order until another stored order is closer to its view direction by
  // more than this cosine margin (FramePlan::order_hysteresis). 0: off, the paper's rule every frame.
  float order_hysteresis = 0.0f;
  Clipping clipping;       // slab and clip planes (clip_planes.h)
  bool lighting = false;   // illuminated lines (line_lighting.h)
  glm::vec3 background() const { return white_background ? glm::vec3(1.0f) : glm::vec3(0.0f); }
};

}  // namespace vxl
