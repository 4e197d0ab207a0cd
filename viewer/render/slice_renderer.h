// The anatomical image's slices: axis-aligned planes (and optionally the plane facing the view) through
// the focus point, resampled from the volume (a 3D texture sampled through the inverse voxel-to-RAS
// affine), grey-mapped and opaque. Needs only a current OpenGL 3.3 core context.
//
// They are drawn before the lines into a target of their own: colour (the background where no slice is)
// and, in a second attachment, the window depth of the nearest slice (1 where none). The line shaders
// discard fragments behind that depth (line_shaders.h), which works the same in every transparency mode,
// including the per-pixel lists of `exact`; each mode then composites its lines over the slice colour.
#pragma once

#include <array>
#include <vector>

#include <glm/glm.hpp>

#include "viewer/render/camera.h"
#include "viewer/render/gl_util.h"
#include "viewer/render/render_settings.h"
#include "viewer/render/volume.h"

namespace vxl {

class SliceRenderer {
 public:
  // Uploads the volume. Throws vxl::Error (unsupported, naming volume.name) when it exceeds the GPU's 3D
  // texture size.
  explicit SliceRenderer(const Volume& volume);
  ~SliceRenderer();
  SliceRenderer(const SliceRenderer&) = delete;
  SliceRenderer& operator=(const SliceRenderer&) = delete;

  // Draws the slices `settings` asks for through camera.target into the slice target (width x height),
  // cut by the world half-spaces `clip` ({n, d}: dot(n, p) + d >= 0 kept) like the lines.
  void draw(const Camera& camera, const glm::dmat4& projection, const SliceSettings& settings,
            const std::vector<glm::dvec4>& clip, const glm::vec3& background, int width, int height);
  // Copies the slice colour into the bound framebuffer (a fullscreen pass, no blending).
  void copy_color() const;
  GLuint color_texture() const { return target_.color[0]; }
  GLuint depth_texture() const { return target_.color[1]; }  // R32F window depth, 1: no slice

  std::array<float, 2> range(const SliceSettings& settings) const;
  glm::dvec3 ras_min() const { return ras_min_; }
  glm::dvec3 ras_max() const { return ras_max_; }

 private:
  std::array<std::int64_t, 3> dims_{};
  glm::dmat4 ras_to_voxel_{1.0};
  std::array<glm::dvec3, 8> corners_{};
  glm::dvec3 ras_min_{0.0}, ras_max_{0.0};
  std::array<float, 2> window_{0, 1};
  GLuint texture_ = 0, program_ = 0, copy_program_ = 0, vao_ = 0;
  gl::RenderTarget target_;
};

}  // namespace vxl
