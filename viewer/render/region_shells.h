// Draws the selection's regions (region_shapes.h) as translucent shells, one half at a time: the renderer
// draws the half facing away from the viewer over the picture's base (background or slices) before the
// lines, and the half facing the viewer after them, so that lines inside a region appear between the two
// (docs/rendering.md, "Region shells"). Each half of a convex shape covers a pixel at most once, so it
// blends in one layer. Both halves are hidden behind the opaque slices the way the lines are (the slices'
// depth texture, slice_renderer.h), and by what the framebuffer's depth holds (the opaque mode's lines), and
// cut by the slab and clip planes where the lines are (clip_planes.h).
// Needs only a current OpenGL 3.3 core context.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "viewer/render/camera.h"
#include "viewer/render/clip_planes.h"
#include "viewer/render/gl_util.h"
#include "viewer/render/region_shapes.h"

namespace vxl {

class RegionShells {
 public:
  RegionShells();
  ~RegionShells();
  RegionShells(const RegionShells&) = delete;
  RegionShells& operator=(const RegionShells&) = delete;

  // Blends `half` of every shape over the bound framebuffer (current viewport), the farthest shape first.
  // slice_depth: the slices' depth texture, 0 when no slices are drawn. clip: the world-space half-spaces
  // kept (clip_half_spaces), at most kMaxClipDistances used.
  void draw(const Camera& camera, const glm::dmat4& projection, const std::vector<RegionShape>& shapes, ShellHalf half,
            GLuint slice_depth, const std::vector<glm::dvec4>& clip);

 private:
  GLuint program_ = 0, vao_ = 0, buffer_ = 0;
  GLint sphere_first_ = 0, sphere_count_ = 0, box_first_ = 0, box_count_ = 0;
};

}  // namespace vxl
