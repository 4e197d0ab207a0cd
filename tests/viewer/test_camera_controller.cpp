// The window's camera controller without a window: orbit, zoom and pan from synthetic mouse input.
#include <cmath>

#include <gtest/gtest.h>

#include "viewer/app/camera_controller.h"

namespace vxl::app {
namespace {

constexpr int kWidth = 800, kHeight = 600;

Camera front_camera(bool orthographic = false) {
  Camera c;
  c.target = glm::dvec3(10.0, -20.0, 30.0);
  c.distance = 300.0;
  c.ortho_height = 200.0;
  c.orthographic = orthographic;
  return c;  // azimuth 0, elevation 0: looking from anterior
}

CameraController controller(const Camera& c) {
  CameraController k(c, 100.0);
  k.set_window_height(kHeight);
  return k;
}

void drag(CameraController& k, DragMode mode, double dx, double dy) {
  k.begin_drag(mode, 400, 300);
  k.drag_to(400 + dx, 300 + dy);
  k.end_drag();
}

// Window pixel (x right, y down) where `camera` shows world point p.
glm::dvec2 to_window(const Camera& camera, const glm::dvec3& p) {
  const glm::dvec3 e = glm::dmat3(camera.view_rotation()) * (p - camera.eye());
  const glm::dvec4 clip = glm::dmat4(camera.projection(double(kWidth) / kHeight, 1.0, 1000.0)) * glm::dvec4(e, 1.0);
  const glm::dvec2 ndc = glm::dvec2(clip) / clip.w;
  return {(ndc.x + 1) / 2 * kWidth, (1 - ndc.y) / 2 * kHeight};
}

double visible_height(const Camera& c) {
  return c.orthographic ? c.ortho_height : 2 * c.distance * std::tan(c.fov_y_deg * 3.14159265358979323846 / 360);
}

TEST(CameraController, DragRightIncreasesAzimuthAndTurnsTheSceneRight) {
  CameraController k = controller(front_camera());
  const Camera before = k.camera();
  drag(k, DragMode::Orbit, 10, 0);
  EXPECT_NEAR(k.camera().azimuth_deg, 10 * CameraController::kDegreesPerPixel, 1e-12);
  EXPECT_DOUBLE_EQ(k.camera().elevation_deg, 0.0);
  // The eye went towards screen left, so the scene turned with the cursor.
  EXPECT_LT(glm::dot(k.camera().eye() - before.eye(), before.right()), 0.0);
  EXPECT_EQ(k.camera().target, before.target);
  EXPECT_DOUBLE_EQ(k.camera().distance, before.distance);
}

TEST(CameraController, DragDownRaisesTheEyeAndElevationIsClamped) {
  CameraController k = controller(front_camera());
  drag(k, DragMode::Orbit, 0, 25);
  EXPECT_NEAR(k.camera().elevation_deg, 25 * CameraController::kDegreesPerPixel, 1e-12);
  EXPECT_GT(k.camera().eye().z, k.camera().target.z);

  drag(k, DragMode::Orbit, 0, 5000);
  EXPECT_DOUBLE_EQ(k.camera().elevation_deg, 90.0);
  // At the pole the screen axes are still well defined.
  EXPECT_NEAR(glm::length(k.camera().up()), 1.0, 1e-12);
  EXPECT_NEAR(glm::dot(k.camera().up(), k.camera().forward()), 0.0, 1e-12);

  drag(k, DragMode::Orbit, 0, -10000);
  EXPECT_DOUBLE_EQ(k.camera().elevation_deg, -90.0);
}

TEST(CameraController, AzimuthWrapsAround) {
  CameraController k = controller(front_camera());
  drag(k, DragMode::Orbit, 460 / CameraController::kDegreesPerPixel, 0);  // +460 degrees
  EXPECT_NEAR(k.camera().azimuth_deg, 100.0, 1e-9);
  drag(k, DragMode::Orbit, -400 / CameraController::kDegreesPerPixel, 0);  // 100 - 400 = -300 = +60
  EXPECT_NEAR(k.camera().azimuth_deg, 60.0, 1e-9);
}

TEST(CameraController, EveryMoveOfOneDragCounts) {
  CameraController k = controller(front_camera());
  k.begin_drag(DragMode::Orbit, 0, 0);
  k.drag_to(5, 0);
  k.drag_to(12, 0);
  k.end_drag();
  k.drag_to(100, 0);  // no button held: nothing happens
  EXPECT_NEAR(k.camera().azimuth_deg, 12 * CameraController::kDegreesPerPixel, 1e-12);
  EXPECT_EQ(k.dragging(), DragMode::None);
}

TEST(CameraController, WheelZoomsDistanceInPerspectiveAndHeightInOrthographic) {
  CameraController k = controller(front_camera());
  k.zoom(1);
  EXPECT_NEAR(k.camera().distance, 300.0 / CameraController::kZoomPerStep, 1e-9);
  EXPECT_DOUBLE_EQ(k.camera().ortho_height, 200.0);
  k.zoom(-2);
  EXPECT_NEAR(k.camera().distance, 300.0 * CameraController::kZoomPerStep, 1e-9);

  CameraController o = controller(front_camera(true));
  o.zoom(3);
  EXPECT_NEAR(o.camera().ortho_height, 200.0 / std::pow(CameraController::kZoomPerStep, 3), 1e-9);
  EXPECT_DOUBLE_EQ(o.camera().distance, 300.0);
}

TEST(CameraController, ZoomIsBounded) {
  CameraController k = controller(front_camera());
  k.zoom(1000);
  EXPECT_GT(k.camera().distance, 0.0);
  EXPECT_TRUE(std::isfinite(k.camera().distance));
  k.zoom(-1000);
  EXPECT_TRUE(std::isfinite(k.camera().distance));
  EXPECT_LE(k.camera().distance, 100.0 * 100.0);
}

TEST(CameraController, PanMovesTheTargetInTheScreenPlaneAndTheSceneFollowsTheCursor) {
  for (bool orthographic : {false, true}) {
    SCOPED_TRACE(orthographic ? "orthographic" : "perspective");
    Camera start = front_camera(orthographic);
    start.azimuth_deg = -35;
    start.elevation_deg = 25;
    CameraController k = controller(start);
    const glm::dvec3 anchor = start.target;  // shown at the window centre
    drag(k, DragMode::Pan, 40, -15);

    const glm::dvec3 moved = k.camera().target - start.target;
    EXPECT_GT(glm::length(moved), 0.0);
    EXPECT_NEAR(glm::dot(moved, start.forward()), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(moved), std::hypot(40.0, 15.0) * visible_height(start) / kHeight, 1e-9);
    EXPECT_DOUBLE_EQ(k.camera().azimuth_deg, start.azimuth_deg);
    EXPECT_DOUBLE_EQ(k.camera().distance, start.distance);

    // Within float precision: the camera's rotation and projection matrices are single precision.
    const glm::dvec2 p = to_window(k.camera(), anchor);
    EXPECT_NEAR(p.x, kWidth / 2 + 40.0, 1e-3);
    EXPECT_NEAR(p.y, kHeight / 2 - 15.0, 1e-3);
  }
}

TEST(CameraController, SwitchingProjectionKeepsTheScaleAtTheTarget) {
  CameraController k = controller(front_camera());
  const double h = visible_height(k.camera());
  k.set_orthographic(true);
  EXPECT_TRUE(k.camera().orthographic);
  EXPECT_NEAR(k.camera().ortho_height, h, 1e-9);
  k.zoom(2);
  const double h2 = visible_height(k.camera());
  k.set_orthographic(false);
  EXPECT_FALSE(k.camera().orthographic);
  EXPECT_NEAR(visible_height(k.camera()), h2, 1e-9);
}

TEST(CameraController, ViewPresetsAndReset) {
  const Camera home = front_camera();
  CameraController k = controller(home);
  k.set_view(180, 90);
  EXPECT_DOUBLE_EQ(k.camera().azimuth_deg, 180.0);
  EXPECT_DOUBLE_EQ(k.camera().elevation_deg, 90.0);
  EXPECT_EQ(k.camera().target, home.target);
  drag(k, DragMode::Pan, 10, 10);
  k.zoom(3);
  k.reset();
  EXPECT_EQ(k.camera().target, home.target);
  EXPECT_DOUBLE_EQ(k.camera().distance, home.distance);
  EXPECT_DOUBLE_EQ(k.camera().azimuth_deg, home.azimuth_deg);
}

}  // namespace
}  // namespace vxl::app
