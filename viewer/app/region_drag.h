// The geometry of dragging a selection sphere with the mouse in the voxview window: the ray under the
// cursor, which sphere it hits first, and how far a drag moves the sphere's centre in the plane that
// faces the viewer through it (so the sphere stays under the cursor, at its depth). Pure math, no GL, no
// GLFW: the window calls it, the tests drive it. Window positions are input pixels, y down, as GLFW
// reports them; the window's width and height in the same pixels.
#pragma once

#include <cstddef>
#include <optional>
#include <span>

#include <glm/glm.hpp>

#include "viewer/render/camera.h"
#include "viewer/render/region_shapes.h"

namespace vxl::app {

struct PickRay {
  glm::dvec3 origin;
  glm::dvec3 direction;  // unit
};

// The ray from the eye (orthographic: from the view plane through the eye) through window point (x, y).
PickRay pick_ray(const Camera& camera, double x, double y, int width, int height);

// The distance along `ray` to where it first enters the sphere, 0 when its origin is inside; none when
// it misses it (or the sphere lies behind the origin).
std::optional<double> ray_sphere_hit(const PickRay& ray, const glm::dvec3& centre, double radius);

// The sphere of `shapes` the ray hits first (boxes are not picked); none when it hits none.
std::optional<std::size_t> pick_sphere(const PickRay& ray, std::span<const RegionShape> shapes);

// The move of a point at `point` dragged by the cursor from `from` to `to` (window positions), in the
// plane through `point` facing the viewer: the point under the cursor stays under it. Zero when either
// ray runs along the plane or meets it behind the eye.
glm::dvec3 drag_in_view_plane(const Camera& camera, const glm::dvec3& point, const glm::dvec2& from,
                              const glm::dvec2& to, int width, int height);

}  // namespace vxl::app
