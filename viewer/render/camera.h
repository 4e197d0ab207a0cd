// Orbit camera in RAS mm. Positions are kept in double; the renderer subtracts the eye position in double
// (split into a float high part and a float low part) so that a tractogram far from the origin keeps the
// precision of its source (spec §8).
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>

#include <glm/glm.hpp>

namespace vxl {

struct Camera {
  glm::dvec3 target{0.0};
  double distance = 300.0;     // mm from target to eye
  double azimuth_deg = 0.0;    // rotation about +Z (superior); 0 looks from anterior (+Y)
  double elevation_deg = 0.0;  // +90 looks from superior
  double fov_y_deg = 30.0;     // perspective field of view
  bool orthographic = false;
  double ortho_height = 200.0;  // mm visible vertically in orthographic mode

  glm::dvec3 eye() const;
  glm::dvec3 forward() const;  // unit, eye -> target
  glm::dvec3 up() const;       // unit, screen up
  glm::dvec3 right() const;    // unit, screen right

  // Rotation from world to eye space (rows: right, up, -forward). Applied to camera-relative positions.
  glm::mat3 view_rotation() const;
  glm::mat4 projection(double aspect, double near_mm, double far_mm) const;

  // Frames an axis-aligned box: target at its centre, distance/ortho size so that its bounding sphere fits
  // from any direction (the benchmarks' turntables rely on that).
  void frame(const glm::dvec3& box_min, const glm::dvec3& box_max, double aspect);

  // For the current direction and projection: moves the target across the view and sets the distance (and
  // ortho_height) so that `points` fill the window, kFrameMargin of each half-extent left free along the
  // tighter of width and height, centred in both. The target's depth is the middle of the points' depths.
  void frame_points(std::span<const glm::dvec3> points, double aspect);
  // The same with the target kept at `pivot` (the picture centred on it): for views that turn about it.
  void frame_points_about(std::span<const glm::dvec3> points, const glm::dvec3& pivot, double aspect);

  static constexpr double kFrameMargin = 0.04;
};

// The views drawn. Beyond these a double no longer gives a picture (an azimuth of 1e308 degrees has no
// angle left, a target or distance of 1e308 mm puts every line on one pixel, a field of view or a slab of
// 1e-300 shows nothing), so view files and options outside them are refused.
struct ViewLimits {
  static constexpr double kMaxMm = 1e7;   // |target| per axis, distance, ortho height, slab: 10 km
  static constexpr double kMinMm = 1e-3;  // distance, ortho height, slab when on: 1 micrometre
  static constexpr double kMaxAzimuthDeg = 1e6;
  static constexpr double kMinFovDeg = 1, kMaxFovDeg = 179;
};

// The view a picture or a window opens with when none is given: {azimuth, elevation} in degrees, from the
// front left and above, so that the three axes' directions all show.
inline constexpr std::array<double, 2> kDefaultView{-35.0, 25.0};

// Standard views (anterior up in axial views, patient right on screen right seen from above) like mrview's:
// "axial"/"superior", "inferior", "sagittal"/"left", "right", "coronal"/"anterior", "posterior", or "AZ,EL" in degrees
// (elevation clamped to [-90, 90]; an azimuth beyond ViewLimits is no view). Returns {azimuth, elevation}.
std::optional<std::array<double, 2>> parse_view(const std::string& name);
// The standard views' names, each other name in brackets: "axial (superior), inferior, sagittal (left), ...".
std::string view_names_text();

}  // namespace vxl
