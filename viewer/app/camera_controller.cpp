#include "viewer/app/camera_controller.h"

#include <algorithm>
#include <cmath>

namespace vxl::app {

namespace {
constexpr double kPi = 3.14159265358979323846;

// Height (mm) of the picture at the target plane, for either projection.
double visible_height(const Camera& c) {
  return c.orthographic ? c.ortho_height : 2.0 * c.distance * std::tan(c.fov_y_deg * kPi / 360.0);
}

double wrap_degrees(double a) {
  a = std::fmod(a, 360.0);
  if (a > 180.0) a -= 360.0;
  if (a <= -180.0) a += 360.0;
  return a;
}
}  // namespace

CameraController::CameraController(const Camera& home, double scene_radius) : camera_(home), home_(home) {
  const double r = std::max(scene_radius, 1e-3);
  min_extent_ = r * 1e-3;  // a few microns across for a 10 cm scene: closer than anyone needs
  max_extent_ = r * 100.0;
}

double CameraController::mm_per_pixel() const { return visible_height(camera_) / window_height_; }

void CameraController::begin_drag(DragMode mode, double x, double y) {
  drag_ = mode;
  last_x_ = x;
  last_y_ = y;
}

void CameraController::drag_to(double x, double y) {
  const double dx = x - last_x_, dy = y - last_y_;
  last_x_ = x;
  last_y_ = y;
  if (drag_ == DragMode::Orbit) {
    camera_.azimuth_deg = wrap_degrees(camera_.azimuth_deg + dx * kDegreesPerPixel);
    camera_.elevation_deg = std::clamp(camera_.elevation_deg + dy * kDegreesPerPixel, -90.0, 90.0);
  } else if (drag_ == DragMode::Pan) {
    // Moving the target against the drag moves the scene with it; window y grows downwards.
    const double s = mm_per_pixel();
    camera_.target += (-dx * camera_.right() + dy * camera_.up()) * s;
  }
}

void CameraController::zoom(double steps) {
  const double factor = std::pow(kZoomPerStep, -steps);
  if (camera_.orthographic)
    camera_.ortho_height = std::clamp(camera_.ortho_height * factor, min_extent_, 2 * max_extent_);
  else
    camera_.distance = std::clamp(camera_.distance * factor, min_extent_, max_extent_);
}

void CameraController::set_view(double azimuth_deg, double elevation_deg) {
  camera_.azimuth_deg = wrap_degrees(azimuth_deg);
  camera_.elevation_deg = std::clamp(elevation_deg, -90.0, 90.0);
}

void CameraController::set_orthographic(bool orthographic) {
  if (orthographic == camera_.orthographic) return;
  const double tan_half = std::tan(camera_.fov_y_deg * kPi / 360.0);
  if (orthographic)
    camera_.ortho_height = std::clamp(2.0 * camera_.distance * tan_half, min_extent_, 2 * max_extent_);
  else
    camera_.distance = std::clamp(camera_.ortho_height / (2.0 * tan_half), min_extent_, max_extent_);
  camera_.orthographic = orthographic;
}

}  // namespace vxl::app
