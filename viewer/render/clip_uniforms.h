// The slab and clip half-spaces (clip_planes.h) as the shaders of lines, slices and region shells take them:
// camera-relative in u_clip / u_clip_count, one gl_ClipDistance each. Needs a current GL context.
#pragma once

#include <span>

#include <glm/glm.hpp>
#include "viewer/render/gl_api.h"

namespace vxl {

// Uploads `half_spaces` (world space, at most kMaxClipDistances used) relative to `eye` to `program` (in use) and
// enables as many clip distances; returns how many.
int bind_clip_half_spaces(GLuint program, std::span<const glm::dvec4> half_spaces, const glm::dvec3& eye);

// Enables gl_ClipDistance 0 .. n - 1 and disables the others (0: a pass that writes none).
void enable_clip_distances(int n);

}  // namespace vxl
