// Crop to slab and clip planes: which part of the scene the user wants to see.
//
//   slab   a slab of `slab_mm` thickness centred on the camera's target (the focus point), perpendicular
//          to the view direction — mrview's "crop to slab". It turns with the camera; moving the focus
//          along the view direction moves it through the scene.
//   planes up to three axis-aligned half-spaces in RAS mm: "+x at 10" keeps x >= 10, "-x at 10" keeps
//          x <= 10 (DSI Studio's and NiiVue's clip planes).
//
// Both act twice: the frame plan drops every voxel whose tight box lies wholly outside (no voxel drawn
// that the view cannot show), and the line shader clips what remains exactly (gl_ClipDistance), so a
// voxel that straddles a plane is cut at the plane.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace vxl {

struct Camera;

struct AxisClip {
  int axis = 0;            // 0 x, 1 y, 2 z
  bool keep_above = true;  // true: keep coordinate >= position (+axis); false: keep <= position (-axis)
  double position = 0;     // RAS mm
  bool enabled = true;     // the window toggles planes without forgetting them
  bool operator==(const AxisClip&) const = default;
};

struct Clipping {
  static constexpr int kMaxPlanes = 3;
  double slab_mm = 0;            // 0: no slab
  std::vector<AxisClip> planes;  // at most kMaxPlanes
  bool active() const;
  bool operator==(const Clipping&) const = default;
};

// Half-spaces the picture keeps, at most 2 + kMaxPlanes.
inline constexpr int kMaxClipDistances = 2 + Clipping::kMaxPlanes;

// "x,12.5", "-z,0", "+y,-3" -> AxisClip; nullopt when malformed (the caller names the option).
std::optional<AxisClip> parse_axis_clip(const std::string& text);
// The inverse of parse_axis_clip: "x,12.5" / "-z,0".
std::string axis_clip_text(const AxisClip& clip);

// World-space half-spaces {n, d} kept where dot(n, p) + d >= 0: the slab's two faces (when on), then
// each enabled plane. n is a unit vector.
std::vector<glm::dvec4> clip_half_spaces(const Clipping& clipping, const Camera& camera);

// The same half-space relative to a point `origin` (the eye): dot(n, p - origin) + d' >= 0. Computed in
// double, so the float copy the shader gets keeps the source precision far from the origin.
glm::dvec4 relative_to(const glm::dvec4& half_space, const glm::dvec3& origin);

}  // namespace vxl
