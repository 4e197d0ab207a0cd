#include "viewer/render/view_queries.h"

#include <algorithm>

#include "format/vxl_file.h"

namespace vxl {

SceneBounds line_bounds(std::span<const VxlFile* const> files) {
  SceneBounds b;
  bool any = false;
  for (const VxlFile* f : files) {
    const MetaSection& m = f->meta();
    if (m.point_count == 0) continue;
    const glm::dvec3 lo(m.bounds_min[0], m.bounds_min[1], m.bounds_min[2]);
    const glm::dvec3 hi(m.bounds_max[0], m.bounds_max[1], m.bounds_max[2]);
    b.min = any ? glm::min(b.min, lo) : lo;
    b.max = any ? glm::max(b.max, hi) : hi;
    any = true;
  }
  return b;
}

SceneBounds scene_bounds(std::span<const VxlFile* const> files, const Volume* volume) {
  SceneBounds b = line_bounds(files);
  if (volume) {
    b.min = glm::min(b.min, volume->ras_min());
    b.max = glm::max(b.max, volume->ras_max());
  }
  return b;
}

glm::dmat4 fitted_projection(const Camera& camera, double aspect, const SceneBounds& scene, double voxel_size) {
  // The margin is a voxel, but never more than the scene's own size: every vertex lies inside the bounds,
  // and a voxel far larger than the scene (--voxel-size 1e8) would put the near plane (far · 1e-4) beyond
  // every line.
  const double half_diagonal = glm::length(scene.max - scene.min) * 0.5;
  const double radius = std::max(1.0, half_diagonal + std::min(voxel_size, std::max(1.0, half_diagonal)));
  return projection_around(camera, aspect, (scene.min + scene.max) * 0.5, radius);
}

glm::dmat4 projection_around(const Camera& camera, double aspect, const glm::dvec3& centre, double radius) {
  const double along = glm::dot(centre - camera.eye(), camera.forward());
  const double far_mm = along + radius;
  const double near_mm = camera.orthographic ? along - radius : std::max(far_mm * 1e-4, along - radius);
  return glm::dmat4(Camera(camera).projection(aspect, near_mm, std::max(far_mm, near_mm + 1.0)));
}

void plan_view(const SceneLayout& layout, const Camera& camera, const glm::dmat4& projection, PlanOrder order,
               FramePlan& out, const Clipping& clipping) {
  ViewParams view = make_view_params(camera.eye(), camera.forward(), camera.orthographic, projection,
                                     glm::dmat3(camera.view_rotation()));
  for (const glm::dvec4& h : clip_half_spaces(clipping, camera)) view.clip.push_back(relative_to(h, view.eye));
  plan_frame(layout, view, order, out);
}

std::vector<std::uint32_t> spans_nearest_first(const SceneLayout& layout, const FramePlan& plan) {
  std::vector<std::uint32_t> needed;
  std::vector<bool> seen(layout.texture_spans().size(), false);
  for (std::size_t i = plan.first.size(); i-- > 0;) {
    const std::uint32_t span = layout.span_of_id(plan.first[i]);
    if (!seen[span]) needed.push_back(span);
    seen[span] = true;
  }
  return needed;
}

std::uint64_t view_bytes(const SceneLayout& layout, const Camera& camera, double aspect, const SceneBounds& scene,
                         const Clipping& clipping) {
  FramePlan visible;
  plan_view(layout, camera, fitted_projection(camera, aspect, scene, layout.voxel_size()), PlanOrder::Any, visible,
            clipping);
  std::uint64_t bytes = 0;
  for (std::uint32_t span : spans_nearest_first(layout, visible)) bytes += layout.span_upload_bytes(span);
  return bytes;
}

}  // namespace vxl
