#include "viewer/app/region_drag.h"

#include <algorithm>
#include <cmath>

namespace vxl::app {
namespace {

// Where `ray` meets the plane through `point` with normal `normal`; none when parallel or behind.
std::optional<glm::dvec3> hit_plane(const PickRay& ray, const glm::dvec3& point, const glm::dvec3& normal) {
  const double along = glm::dot(ray.direction, normal);
  if (std::abs(along) < 1e-12) return std::nullopt;
  const double t = glm::dot(point - ray.origin, normal) / along;
  if (t < 0) return std::nullopt;
  return ray.origin + t * ray.direction;
}

}  // namespace

PickRay pick_ray(const Camera& camera, double x, double y, int width, int height) {
  const double w = std::max(1, width), h = std::max(1, height);
  const double nx = 2.0 * x / w - 1.0, ny = 1.0 - 2.0 * y / h;  // the picture's [-1, 1] square, y up
  const double aspect = w / h;
  if (camera.orthographic) {
    const double half = camera.ortho_height / 2;
    return {camera.eye() + camera.right() * (nx * half * aspect) + camera.up() * (ny * half), camera.forward()};
  }
  const double half = std::tan(glm::radians(camera.fov_y_deg) / 2);
  const glm::dvec3 d = camera.forward() + camera.right() * (nx * half * aspect) + camera.up() * (ny * half);
  return {camera.eye(), glm::normalize(d)};
}

std::optional<double> ray_sphere_hit(const PickRay& ray, const glm::dvec3& centre, double radius) {
  // |o + t d - c|^2 = r^2 with |d| = 1: t^2 + 2 b t + k = 0, b = d.(o - c), k = |o - c|^2 - r^2.
  const glm::dvec3 oc = ray.origin - centre;
  const double b = glm::dot(ray.direction, oc), k = glm::dot(oc, oc) - radius * radius;
  if (k <= 0) return 0.0;  // inside
  const double disc = b * b - k;
  if (disc < 0) return std::nullopt;
  const double t = -b - std::sqrt(disc);
  if (t < 0) return std::nullopt;  // both crossings behind the origin (k > 0: the same sign)
  return t;
}

std::optional<std::size_t> pick_sphere(const PickRay& ray, std::span<const RegionShape> shapes) {
  std::optional<std::size_t> best;
  double best_t = 0;
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    if (shapes[i].kind != RegionShape::Kind::Sphere) continue;
    const auto t = ray_sphere_hit(ray, shapes[i].centre, shapes[i].radius);
    if (t && (!best || *t < best_t)) best = i, best_t = *t;
  }
  return best;
}

glm::dvec3 drag_in_view_plane(const Camera& camera, const glm::dvec3& point, const glm::dvec2& from,
                              const glm::dvec2& to, int width, int height) {
  const glm::dvec3 normal = camera.forward();
  const auto a = hit_plane(pick_ray(camera, from.x, from.y, width, height), point, normal);
  const auto b = hit_plane(pick_ray(camera, to.x, to.y, width, height), point, normal);
  if (!a || !b) return glm::dvec3(0.0);
  return *b - *a;
}

}  // namespace vxl::app
