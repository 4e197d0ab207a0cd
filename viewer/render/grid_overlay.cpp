#include "viewer/render/grid_overlay.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/type_ptr.hpp>

#include "viewer/render/camera.h"
#include "viewer/render/renderer.h"
#include "viewer/render/view_queries.h"

namespace vxl {

namespace {

const char* const kVertex = R"(#version 330 core
layout(location = 0) in vec3 a_corner;   // unit-cube corner, each component 0 or 1
layout(location = 1) in ivec3 a_coord;   // the voxel's integer grid coordinate (per instance)
uniform ivec3 u_eye_cell;                // the eye in grid units: integer part ...
uniform vec3 u_eye_frac;                 // ... and fractional part
uniform float u_voxel_size;
uniform mat3 u_rotation;
uniform mat4 u_projection;
void main() {
  vec3 rel = (vec3(a_coord - u_eye_cell) + (a_corner - u_eye_frac)) * u_voxel_size;
  gl_Position = u_projection * vec4(u_rotation * rel, 1.0);
}
)";

const char* const kFragment = R"(#version 330 core
uniform vec4 u_colour;
out vec4 frag;
void main() { frag = u_colour; }
)";

// The 12 edges of the unit cube as 24 line end points.
std::vector<float> cube_edges() {
  std::vector<float> v;
  for (int axis = 0; axis < 3; ++axis)
    for (int i = 0; i < 4; ++i) {
      // the two other axes take the four combinations of 0/1; `axis` runs 0 -> 1
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      for (int end = 0; end < 2; ++end) {
        float p[3];
        p[axis] = static_cast<float>(end);
        p[a] = static_cast<float>(i & 1);
        p[b] = static_cast<float>(i >> 1);
        v.insert(v.end(), p, p + 3);
      }
    }
  return v;
}

}  // namespace

GridOverlay::GridOverlay(const Renderer& renderer) : GridOverlay(std::span<const VxlFile* const>(renderer.files())) {}

GridOverlay::GridOverlay(std::span<const VxlFile* const> files) : files_(files.begin(), files.end()) {
  program_ = gl::make_program(kVertex, kFragment);
  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);

  const std::vector<float> edges = cube_edges();
  glGenBuffers(1, &corners_);
  glBindBuffer(GL_ARRAY_BUFFER, corners_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(edges.size() * sizeof(float)), edges.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribDivisor(1, 1);

  // Every voxel's coordinate, straight from the voxel tables (file after file): uploaded once for the "all"
  // scope.
  std::vector<glm::ivec3> all;
  for (const VxlFile* f : files_) {
    all_first_.push_back(all.size());
    for (const VoxelEntry& e : f->voxels()) all.emplace_back(e.coord[0], e.coord[1], e.coord[2]);
  }
  voxel_count_ = all.size();
  glGenBuffers(1, &all_instances_);
  glBindBuffer(GL_ARRAY_BUFFER, all_instances_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(all.size() * sizeof(glm::ivec3)), all.data(), GL_STATIC_DRAW);
  glGenBuffers(1, &drawn_instances_);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindVertexArray(0);
}

std::optional<std::size_t> GridOverlay::index_of(const VxlFile* file) const {
  const auto it = std::find(files_.begin(), files_.end(), file);
  if (it == files_.end()) return std::nullopt;
  return static_cast<std::size_t>(it - files_.begin());
}

GridOverlay::~GridOverlay() {
  const GLuint buffers[3] = {corners_, all_instances_, drawn_instances_};
  glDeleteBuffers(3, buffers);
  if (vao_) glDeleteVertexArrays(1, &vao_);
  if (program_) glDeleteProgram(program_);
}

void GridOverlay::draw(const Renderer& renderer, const Camera& camera, double aspect, Scope scope,
                       const glm::vec4& colour, const Clipping& clipping) {
  const SceneLayout& layout = renderer.layout();
  // Per overlay file: the first instance and the count in the instance buffer (each file has its own grid).
  std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges(files_.size(), {0, 0});
  GLuint instances = all_instances_;
  cubes_drawn_ = voxel_count_;
  if (scope == Scope::Drawn) {
    // The same cull as the frame; the sort does not matter for outlines. Grouped by file; the renderer's files
    // that are not the overlay's (a focus copy) are left out.
    renderer.plan(camera, aspect, PlanOrder::Any, plan_, clipping);
    drawn_coords_.clear();
    for (std::uint32_t fi = 0; fi < renderer.files().size(); ++fi) {
      const std::optional<std::size_t> mine = index_of(renderer.files()[fi]);
      if (!mine) continue;
      const std::uint64_t first = drawn_coords_.size();
      const auto voxels = renderer.files()[fi]->voxels();
      for (const auto& [key, i] : plan_.sort_keys)
        if (layout.file_of(i) == fi) {
          const VoxelEntry& e = voxels[layout.local_voxel(i)];
          drawn_coords_.emplace_back(e.coord[0], e.coord[1], e.coord[2]);
        }
      ranges[*mine] = {first, drawn_coords_.size() - first};
    }
    glBindBuffer(GL_ARRAY_BUFFER, drawn_instances_);
    // Orphan and refill: a fresh store each frame avoids waiting on the previous frame's draw.
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(drawn_coords_.size() * sizeof(glm::ivec3)),
                 drawn_coords_.data(), GL_STREAM_DRAW);
    instances = drawn_instances_;
    cubes_drawn_ = drawn_coords_.size();
  } else {
    for (std::size_t i = 0; i < files_.size(); ++i) ranges[i] = {all_first_[i], files_[i]->voxels().size()};
  }
  if (cubes_drawn_ == 0) return;

  // Near/far planes of our own: outlines reach up to a voxel beyond the tight bounds the renderer fits its
  // planes to. Depth is not tested, so only clipping matters.
  const glm::dvec3 lo = renderer.bounds_min(), hi = renderer.bounds_max();
  const glm::mat4 projection(
      projection_around(camera, aspect, (lo + hi) * 0.5, glm::length(hi - lo) * 0.5 + 2.0 * layout.voxel_size()));
  const glm::mat3 rotation = camera.view_rotation();

  glUseProgram(program_);
  glUniformMatrix3fv(glGetUniformLocation(program_, "u_rotation"), 1, GL_FALSE, glm::value_ptr(rotation));
  glUniformMatrix4fv(glGetUniformLocation(program_, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
  glUniform4fv(glGetUniformLocation(program_, "u_colour"), 1, glm::value_ptr(colour));
  glBindVertexArray(vao_);
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  glLineWidth(1.0f);
  for (std::size_t fi = 0; fi < ranges.size(); ++fi) {
    const auto [first, count] = ranges[fi];
    if (count == 0) continue;
    const MetaSection& m = files_[fi]->meta();
    // The eye in this file's grid units, split in double into an integer cell and a fraction.
    const glm::dvec3 g =
        (camera.eye() - glm::dvec3(m.grid_origin[0], m.grid_origin[1], m.grid_origin[2])) / m.voxel_size;
    const glm::dvec3 cell = glm::floor(g);
    const glm::ivec3 eye_cell(cell);
    const glm::vec3 eye_frac(g - cell);
    glUniform3iv(glGetUniformLocation(program_, "u_eye_cell"), 1, glm::value_ptr(eye_cell));
    glUniform3fv(glGetUniformLocation(program_, "u_eye_frac"), 1, glm::value_ptr(eye_frac));
    glUniform1f(glGetUniformLocation(program_, "u_voxel_size"), static_cast<float>(m.voxel_size));
    glBindBuffer(GL_ARRAY_BUFFER, instances);
    glVertexAttribIPointer(1, 3, GL_INT, 0, reinterpret_cast<const void*>(first * sizeof(glm::ivec3)));
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    glDrawArraysInstanced(GL_LINES, 0, 24, static_cast<GLsizei>(count));
  }
  glDisable(GL_BLEND);
  glBindVertexArray(0);
}

}  // namespace vxl
