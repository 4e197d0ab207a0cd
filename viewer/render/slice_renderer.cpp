#include "viewer/render/slice_renderer.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/gtc/type_ptr.hpp>

#include "format/base/error.h"
#include "viewer/render/clip_planes.h"
#include "viewer/render/clip_uniforms.h"
#include "viewer/render/line_shaders.h"

namespace vxl {
namespace {

const std::string kSliceVertex = "#version 330 core\n#define CLIPS " + std::to_string(kMaxClipDistances) + R"(
uniform vec3 u_corner[4];   // eye-relative RAS mm (subtracted in double on the CPU)
uniform vec3 u_voxel[4];    // the same corners in voxel coordinates
uniform mat3 u_rotation;
uniform mat4 u_projection;
uniform vec4 u_clip[CLIPS];
uniform int u_clip_count;
#if CLIP_DISTANCES
out float gl_ClipDistance[CLIPS];
#endif
out vec3 v_voxel;
void main() {
  vec3 rel = u_corner[gl_VertexID];
#if CLIP_DISTANCES
  for (int i = 0; i < CLIPS; ++i) gl_ClipDistance[i] = i < u_clip_count ? dot(u_clip[i].xyz, rel) + u_clip[i].w : 1.0;
#endif
  v_voxel = u_voxel[gl_VertexID];  // affine in position, so the interpolation is exact
  gl_Position = u_projection * vec4(u_rotation * rel, 1.0);
}
)";

const char* const kSliceFragment = R"(#version 330 core
in vec3 v_voxel;
uniform sampler3D u_volume;
uniform vec3 u_dims;
uniform vec2 u_range;
layout(location = 0) out vec4 colour;
layout(location = 1) out vec4 depth;
void main() {
  vec3 t = (v_voxel + 0.5) / u_dims;
  if (any(lessThan(t, vec3(0.0))) || any(greaterThan(t, vec3(1.0)))) discard;  // outside the image
  float g = clamp((texture(u_volume, t).r - u_range.x) / (u_range.y - u_range.x), 0.0, 1.0);
  colour = vec4(vec3(g), 1.0);
  depth = vec4(gl_FragCoord.z);
}
)";

const char* const kCopyFragment = R"(#version 330 core
uniform sampler2D u_color;
out vec4 frag;
void main() { frag = texelFetch(u_color, ivec2(gl_FragCoord.xy), 0); }
)";

}  // namespace

SliceRenderer::SliceRenderer(const Volume& v)
    : dims_(v.dims),
      ras_to_voxel_(glm::inverse(v.voxel_to_ras)),
      corners_(v.corners()),
      ras_min_(v.ras_min()),
      ras_max_(v.ras_max()),
      window_(v.window) {
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_size);
  for (int a = 0; a < 3; ++a)
    if (dims_[a] < 1 || dims_[a] > max_size)
      fail_unsupported(v.name, "the image is " + std::to_string(dims_[0]) + "x" + std::to_string(dims_[1]) + "x" +
                                   std::to_string(dims_[2]) + " voxels; this GPU's 3D textures hold at most " +
                                   std::to_string(max_size) + " per axis");
  if (v.values.size() != static_cast<std::size_t>(dims_[0] * dims_[1] * dims_[2]))
    throw Error(ErrorKind::Input, v.name, std::nullopt,
                "SliceRenderer: the volume's values do not match its dimensions");
  glGenTextures(1, &texture_);
  glBindTexture(GL_TEXTURE_3D, texture_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexImage3D(GL_TEXTURE_3D, 0, GL_R32F, static_cast<GLsizei>(dims_[0]), static_cast<GLsizei>(dims_[1]),
               static_cast<GLsizei>(dims_[2]), 0, GL_RED, GL_FLOAT, v.values.data());
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  for (GLenum w : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
    glTexParameteri(GL_TEXTURE_3D, w, GL_CLAMP_TO_EDGE);
  glBindTexture(GL_TEXTURE_3D, 0);
  program_ = gl::make_program(kSliceVertex, kSliceFragment);
  copy_program_ = gl::make_program(shaders::kFullscreenVertex, kCopyFragment);
  glGenVertexArrays(1, &vao_);
}

SliceRenderer::~SliceRenderer() {
  for (GLuint p : {program_, copy_program_})
    if (p) glDeleteProgram(p);
  if (texture_) glDeleteTextures(1, &texture_);
  if (vao_) glDeleteVertexArrays(1, &vao_);
  target_.destroy();
}

std::array<float, 2> SliceRenderer::range(const SliceSettings& s) const {
  std::array<float, 2> r = s.range.value_or(window_);
  if (!(r[1] > r[0])) r = {r[0] - 0.5f, r[0] + 0.5f};  // one value only: mid-grey
  return r;
}

void SliceRenderer::draw(const Camera& camera, const glm::dmat4& projection, const SliceSettings& s,
                         const std::vector<glm::dvec4>& clip, const glm::vec3& bg, int width, int height) {
  target_.ensure(width, height, GL_RGBA32F, GL_R32F, true);
  glBindFramebuffer(GL_FRAMEBUFFER, target_.fbo);
  glViewport(0, 0, width, height);
  const GLfloat colour[4] = {bg.r, bg.g, bg.b, 1.0f}, far[4] = {1, 1, 1, 1};
  glClearBufferfv(GL_COLOR, 0, colour);
  glClearBufferfv(GL_COLOR, 1, far);
  glClearDepth(1.0);
  glClear(GL_DEPTH_BUFFER_BIT);
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);

  glUseProgram(program_);
  const glm::dvec3 eye = camera.eye();
  const glm::mat3 rotation = camera.view_rotation();
  const glm::mat4 proj(projection);
  glUniformMatrix3fv(glGetUniformLocation(program_, "u_rotation"), 1, GL_FALSE, glm::value_ptr(rotation));
  glUniformMatrix4fv(glGetUniformLocation(program_, "u_projection"), 1, GL_FALSE, glm::value_ptr(proj));
  glUniform3f(glGetUniformLocation(program_, "u_dims"), float(dims_[0]), float(dims_[1]), float(dims_[2]));
  const std::array<float, 2> r = range(s);
  glUniform2f(glGetUniformLocation(program_, "u_range"), r[0], r[1]);
  bind_clip_half_spaces(program_, clip, eye);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_3D, texture_);
  glUniform1i(glGetUniformLocation(program_, "u_volume"), 0);
  glBindVertexArray(vao_);

  // One quad: corners in triangle-strip order, relative to the eye in double, and in voxel coordinates.
  auto quad = [&](const std::array<glm::dvec3, 4>& world) {
    glm::vec3 rel[4], voxel[4];
    for (int i = 0; i < 4; ++i) {
      rel[i] = glm::vec3(world[i] - eye);
      voxel[i] = glm::vec3(ras_to_voxel_ * glm::dvec4(world[i], 1.0));
    }
    glUniform3fv(glGetUniformLocation(program_, "u_corner"), 4, glm::value_ptr(rel[0]));
    glUniform3fv(glGetUniformLocation(program_, "u_voxel"), 4, glm::value_ptr(voxel[0]));
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  };
  const glm::dvec3 focus = camera.target;
  const bool shown[3] = {s.sagittal, s.coronal, s.axial};  // planes x, y, z = const
  for (int a = 0; a < 3; ++a) {
    if (!shown[a] || focus[a] < ras_min_[a] || focus[a] > ras_max_[a]) continue;
    // The plane's rectangle over the image's RAS box; voxels outside the (possibly oblique) image are
    // discarded per fragment.
    const int u = (a + 1) % 3, w = (a + 2) % 3;
    std::array<glm::dvec3, 4> c;
    for (int i = 0; i < 4; ++i) {
      c[i][a] = focus[a];
      c[i][u] = (i & 1) ? ras_max_[u] : ras_min_[u];
      c[i][w] = (i & 2) ? ras_max_[w] : ras_min_[w];
    }
    quad(c);
  }
  if (s.view_plane) {
    double radius = 0;
    for (const glm::dvec3& p : corners_) radius = std::max(radius, glm::length(p - focus));
    const glm::dvec3 x = camera.right() * radius, y = camera.up() * radius;
    quad({focus - x - y, focus + x - y, focus - x + y, focus + x + y});
  }
  glBindTexture(GL_TEXTURE_3D, 0);
  glDisable(GL_DEPTH_TEST);
  enable_clip_distances(0);
}

void SliceRenderer::copy_color() const {
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
  glUseProgram(copy_program_);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, target_.color[0]);
  glUniform1i(glGetUniformLocation(copy_program_, "u_color"), 0);
  glBindVertexArray(vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

}  // namespace vxl
