// Dragging a selection sphere in the window (region_drag.h): the ray under the cursor, the sphere it
// picks, and the drag's move in the plane facing the viewer, which keeps the point under the cursor —
// checked against the camera's own directions, in perspective and orthographic views. And the editor's
// side: the shapes it hands the renderer, and moving the active sphere by an offset.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "viewer/app/region_drag.h"
#include "viewer/app/region_editor.h"

namespace vxl::app {
namespace {

Camera oblique(bool orthographic) {
  Camera c;
  c.target = {10, -20, 5};
  c.distance = 200;
  c.azimuth_deg = 30;
  c.elevation_deg = 20;
  c.orthographic = orthographic;
  c.ortho_height = 120;
  return c;
}

// The distance from `p` to the line of `ray`.
double off_ray(const PickRay& ray, const glm::dvec3& p) {
  const glm::dvec3 v = p - ray.origin;
  return glm::length(v - glm::dot(v, ray.direction) * ray.direction);
}

TEST(RegionDrag, TheWindowCentreLooksAtTheTarget) {
  for (bool ortho : {false, true}) {
    const Camera c = oblique(ortho);
    const PickRay ray = pick_ray(c, 400, 300, 800, 600);
    EXPECT_NEAR(glm::length(ray.direction), 1.0, 1e-12);
    EXPECT_NEAR(glm::dot(ray.direction, c.forward()), 1.0, 1e-12) << ortho;
    EXPECT_NEAR(off_ray(ray, c.target), 0.0, 1e-9) << ortho;
  }
}

TEST(RegionDrag, ACornerRayMeetsTheFieldOfViewsEdge) {
  Camera c = oblique(false);
  // The top edge of the window is half the vertical field of view above the view direction.
  const PickRay top = pick_ray(c, 400, 0, 800, 600);
  EXPECT_NEAR(std::acos(glm::dot(top.direction, c.forward())), glm::radians(c.fov_y_deg / 2), 1e-9);
  EXPECT_GT(glm::dot(top.direction, c.up()), 0);
  // Orthographic: the right edge lies half the visible width to the right, parallel to the view.
  c.orthographic = true;
  const PickRay right = pick_ray(c, 800, 300, 800, 600);
  EXPECT_NEAR(glm::dot(right.origin - c.eye(), c.right()), c.ortho_height / 2 * 800.0 / 600.0, 1e-9);
  EXPECT_NEAR(glm::dot(right.direction, c.forward()), 1.0, 1e-12);
}

TEST(RegionDrag, RaySphereHitIsTheNearCrossing) {
  const PickRay ray{{0, 0, 0}, {0, 0, 1}};
  ASSERT_TRUE(ray_sphere_hit(ray, {0, 0, 50}, 10).has_value());
  EXPECT_NEAR(*ray_sphere_hit(ray, {0, 0, 50}, 10), 40.0, 1e-12);
  // Off centre by 6 of 10 mm: the crossing is 8 mm before the centre's depth.
  EXPECT_NEAR(*ray_sphere_hit(ray, {6, 0, 50}, 10), 42.0, 1e-12);
  EXPECT_FALSE(ray_sphere_hit(ray, {10.5, 0, 50}, 10).has_value());  // passes beside it
  EXPECT_FALSE(ray_sphere_hit(ray, {0, 0, -50}, 10).has_value());    // behind the eye
  EXPECT_EQ(*ray_sphere_hit(ray, {0, 0, 5}, 10), 0.0);               // the eye inside it
}

TEST(RegionDrag, PickTakesTheNearestSphereAndNoBox) {
  std::vector<RegionShape> shapes(3);
  shapes[0].centre = {0, 0, 80}, shapes[0].radius = 10;
  shapes[1].centre = {0, 0, 50}, shapes[1].radius = 10;
  shapes[2].kind = RegionShape::Kind::Box, shapes[2].lo = {-5, -5, 10}, shapes[2].hi = {5, 5, 20};
  const PickRay ray{{0, 0, 0}, {0, 0, 1}};
  EXPECT_EQ(pick_sphere(ray, shapes), 1u);
  shapes[1].centre.x = 30;  // out of the ray: the far one is hit
  EXPECT_EQ(pick_sphere(ray, shapes), 0u);
  shapes[0].radius = 0.5, shapes[0].centre.x = 2;
  EXPECT_FALSE(pick_sphere(ray, shapes).has_value());
}

TEST(RegionDrag, ADragKeepsThePointUnderTheCursorInTheViewPlane) {
  for (bool ortho : {false, true}) {
    const Camera c = oblique(ortho);
    const glm::dvec3 point = c.target + c.forward() * 30.0 + c.right() * 12.0;  // behind the target, off centre
    const glm::dvec2 from(523, 310), to(611, 255);
    const glm::dvec3 move = drag_in_view_plane(c, point, from, to, 800, 600);
    EXPECT_NEAR(glm::dot(move, c.forward()), 0.0, 1e-9) << ortho;  // stays at its depth
    EXPECT_GT(glm::dot(move, c.right()), 0) << ortho;              // cursor right: the point goes right
    EXPECT_GT(glm::dot(move, c.up()), 0) << ortho;                 // cursor up (y down): up
    // A point under the cursor at `from` is under it at `to` after the move.
    const PickRay a = pick_ray(c, from.x, from.y, 800, 600), b = pick_ray(c, to.x, to.y, 800, 600);
    const double depth = glm::dot(point - a.origin, c.forward()) / glm::dot(a.direction, c.forward());
    const glm::dvec3 under = a.origin + depth * a.direction;
    EXPECT_NEAR(off_ray(b, under + move), 0.0, 1e-9) << ortho;
  }
  // Orthographic: a pixel is ortho_height / window height mm, whatever the depth.
  const Camera c = oblique(true);
  const glm::dvec3 move = drag_in_view_plane(c, c.target + c.forward() * 70.0, {100, 100}, {110, 100}, 800, 600);
  EXPECT_NEAR(glm::length(move), 10 * 120.0 / 600.0, 1e-9);
}

TEST(RegionDrag, EditorShapesMarkTheActiveRegionAndMoveByAnOffset) {
  ViewerOptions o;
  o.include = {"1,2,3,4"};
  o.exclude = {"box:0,0,0,1,2,3"};
  RegionEditor e(o);
  std::vector<RegionShape> shapes = e.shapes();
  ASSERT_EQ(shapes.size(), 2u);
  EXPECT_EQ(shapes[0].kind, RegionShape::Kind::Sphere);
  EXPECT_EQ(shapes[0].role, RegionShape::Role::Include);
  EXPECT_EQ(shapes[0].centre, glm::dvec3(1, 2, 3));
  EXPECT_EQ(shapes[0].radius, 4);
  EXPECT_FALSE(shapes[0].active);
  EXPECT_EQ(shapes[1].kind, RegionShape::Kind::Box);
  EXPECT_EQ(shapes[1].role, RegionShape::Role::Exclude);
  EXPECT_EQ(shapes[1].hi, glm::dvec3(1, 2, 3));
  EXPECT_TRUE(shapes[1].active);  // the last region given

  const std::uint64_t before = e.revision();
  e.move_active_by({1, 1, 1});  // a box does not move
  EXPECT_EQ(e.revision(), before);
  e.activate(0);
  e.move_active_by({0.5, -2, 10});
  EXPECT_EQ(e.shapes()[0].centre, glm::dvec3(1.5, 0, 13));
  EXPECT_TRUE(e.shapes()[0].active);
  EXPECT_NE(e.revision(), before);  // the selection is computed again
}

}  // namespace
}  // namespace vxl::app
