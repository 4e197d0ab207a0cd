#include "viewer/render/region_shells.h"
#include "viewer/render/clip_uniforms.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <glm/gtc/type_ptr.hpp>

namespace vxl {
namespace {

// The slab and clip planes cut the shells exactly as they cut the lines (line_shaders.cpp).
const std::string kShellVertex = "#version 330 core\n#define CLIPS " + std::to_string(kMaxClipDistances) + R"(
layout(location = 0) in vec3 a_position;  // on the unit sphere, or the cube [-1, 1]^3
layout(location = 1) in vec3 a_normal;
uniform vec3 u_centre;  // eye-relative (subtracted in double on the CPU)
uniform vec3 u_scale;   // the radius, or the box's half extents
uniform mat3 u_rotation;
uniform mat4 u_projection;
uniform int u_orthographic;
uniform vec3 u_forward;
uniform vec4 u_clip[CLIPS];  // camera-relative half-spaces: dot(n, p - eye) + d >= 0 is kept
uniform int u_clip_count;
out vec3 v_normal;
out vec3 v_view;  // from the eye towards the surface
#if CLIP_DISTANCES
out float gl_ClipDistance[CLIPS];
#endif
void main() {
  vec3 rel = u_centre + a_position * u_scale;
  v_normal = a_normal;
  v_view = u_orthographic != 0 ? u_forward : rel;
#if CLIP_DISTANCES
  for (int i = 0; i < CLIPS; ++i) gl_ClipDistance[i] = i < u_clip_count ? dot(u_clip[i].xyz, rel) + u_clip[i].w : 1.0;
#endif
  gl_Position = u_projection * vec4(u_rotation * rel, 1.0);
}
)";

// The opacity is region_shell_alpha (region_shapes.cpp) with u_base = region_shell_alpha(1, active).
const char* const kShellFragment = R"(#version 330 core
in vec3 v_normal;
in vec3 v_view;
uniform vec3 u_color;
uniform float u_base;
uniform int u_front;  // 1: the half facing the viewer, 0: the half facing away
uniform sampler2D u_slice_depth;
uniform int u_slice_test;
out vec4 frag;
void main() {
  if (u_slice_test != 0 && gl_FragCoord.z > texelFetch(u_slice_depth, ivec2(gl_FragCoord.xy), 0).r) discard;
  float c = dot(normalize(v_normal), normalize(v_view));  // > 0: the surface faces away from the viewer
  if ((u_front != 0) == (c > 0.0)) discard;
  float rim = 1.0 - clamp(abs(c), 0.0, 1.0);
  frag = vec4(u_color, min(1.0, u_base * (1.0 + 2.0 * rim * rim)));
}
)";

// Triangles as (position, normal) pairs.
void add_sphere(std::vector<glm::vec3>& v) {
  const int rings = 24, sectors = 48;
  auto point = [&](int ring, int sector) {
    const double theta = std::numbers::pi * ring / rings, phi = 2 * std::numbers::pi * sector / sectors;
    return glm::vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
  };
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < sectors; ++s) {
      const glm::vec3 a = point(r, s), b = point(r + 1, s), c = point(r + 1, s + 1), d = point(r, s + 1);
      for (const glm::vec3& p : {a, b, c, a, c, d}) v.insert(v.end(), {p, p});
    }
}

void add_box(std::vector<glm::vec3>& v) {
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {-1.0f, 1.0f}) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      glm::vec3 n(0.0f);
      n[axis] = side;
      auto corner = [&](float a, float b) {
        glm::vec3 p(0.0f);
        p[axis] = side, p[u] = a, p[w] = b;
        return p;
      };
      const glm::vec3 a = corner(-1, -1), b = corner(1, -1), c = corner(1, 1), d = corner(-1, 1);
      for (const glm::vec3& p : {a, b, c, a, c, d}) v.insert(v.end(), {p, n});
    }
}

}  // namespace

RegionShells::RegionShells() {
  program_ = gl::make_program(kShellVertex.c_str(), kShellFragment);
  std::vector<glm::vec3> vertices;
  add_sphere(vertices);
  sphere_count_ = static_cast<GLint>(vertices.size() / 2);
  box_first_ = sphere_count_;
  add_box(vertices);
  box_count_ = static_cast<GLint>(vertices.size() / 2) - box_first_;
  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  glGenBuffers(1, &buffer_);
  glBindBuffer(GL_ARRAY_BUFFER, buffer_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(glm::vec3)), vertices.data(),
               GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 2 * sizeof(glm::vec3), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 2 * sizeof(glm::vec3),
                        reinterpret_cast<const void*>(sizeof(glm::vec3)));
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindVertexArray(0);
}

RegionShells::~RegionShells() {
  if (buffer_) glDeleteBuffers(1, &buffer_);
  if (vao_) glDeleteVertexArrays(1, &vao_);
  if (program_) glDeleteProgram(program_);
}

void RegionShells::draw(const Camera& camera, const glm::dmat4& projection, const std::vector<RegionShape>& shapes,
                        ShellHalf half, GLuint slice_depth, const std::vector<glm::dvec4>& clip) {
  if (shapes.empty()) return;
  const glm::dvec3 eye = camera.eye();
  auto centre = [](const RegionShape& s) {
    return s.kind == RegionShape::Kind::Sphere ? s.centre : (s.lo + s.hi) * 0.5;
  };
  std::vector<const RegionShape*> order;
  for (const RegionShape& s : shapes) order.push_back(&s);
  std::stable_sort(order.begin(), order.end(), [&](const RegionShape* a, const RegionShape* b) {
    return glm::length(centre(*a) - eye) > glm::length(centre(*b) - eye);  // the farthest first
  });

  glUseProgram(program_);
  const glm::mat3 rotation = camera.view_rotation();
  const glm::mat4 proj(projection);
  const glm::vec3 forward(camera.forward());
  glUniformMatrix3fv(glGetUniformLocation(program_, "u_rotation"), 1, GL_FALSE, glm::value_ptr(rotation));
  glUniformMatrix4fv(glGetUniformLocation(program_, "u_projection"), 1, GL_FALSE, glm::value_ptr(proj));
  glUniform1i(glGetUniformLocation(program_, "u_orthographic"), camera.orthographic ? 1 : 0);
  glUniform3fv(glGetUniformLocation(program_, "u_forward"), 1, glm::value_ptr(forward));
  glUniform1i(glGetUniformLocation(program_, "u_front"), half == ShellHalf::Front ? 1 : 0);
  bind_clip_half_spaces(program_, clip, eye);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, slice_depth);
  glUniform1i(glGetUniformLocation(program_, "u_slice_depth"), 0);
  glUniform1i(glGetUniformLocation(program_, "u_slice_test"), slice_depth != 0 ? 1 : 0);
  glBindVertexArray(vao_);

  // Shapes reaching beyond the near and far planes fitted to the scene are kept whole (depth clamped; WebGL2
  // cannot, and the web viewer draws no regions).
#if !VOXLINES_WEBGL
  glEnable(GL_DEPTH_CLAMP);
#endif
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  for (const RegionShape* s : order) {
    const bool sphere = s->kind == RegionShape::Kind::Sphere;
    const glm::vec3 rel(centre(*s) - eye);
    const glm::vec3 scale = sphere ? glm::vec3(float(s->radius)) : glm::vec3((s->hi - s->lo) * 0.5);
    const glm::vec3 color = region_shell_color(s->role);
    glUniform3fv(glGetUniformLocation(program_, "u_centre"), 1, glm::value_ptr(rel));
    glUniform3fv(glGetUniformLocation(program_, "u_scale"), 1, glm::value_ptr(scale));
    glUniform3fv(glGetUniformLocation(program_, "u_color"), 1, glm::value_ptr(color));
    glUniform1f(glGetUniformLocation(program_, "u_base"), region_shell_alpha(1.0f, s->active));
    glDrawArrays(GL_TRIANGLES, sphere ? sphere_first_ : box_first_, sphere ? sphere_count_ : box_count_);
  }
#if !VOXLINES_WEBGL
  glDisable(GL_DEPTH_CLAMP);
#endif
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
  enable_clip_distances(0);
  glBindVertexArray(0);
}

}  // namespace vxl
