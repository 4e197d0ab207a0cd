#include "camera.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include <glm/gtc/matrix_transform.hpp>

namespace vxl {

namespace {
constexpr double kPi = 3.14159265358979323846;
double rad(double deg) { return deg * kPi / 180.0; }
}  // namespace

glm::dvec3 Camera::forward() const {
  // Direction from target to eye for azimuth a, elevation e: (cos e sin a, cos e cos a, sin e).
  double a = rad(azimuth_deg), e = rad(elevation_deg);
  glm::dvec3 to_eye(std::cos(e) * std::sin(a), std::cos(e) * std::cos(a), std::sin(e));
  return -to_eye;
}

glm::dvec3 Camera::eye() const { return target - forward() * distance; }

glm::dvec3 Camera::right() const {
  // Screen right stays horizontal (perpendicular to +Z); at the poles the azimuth still defines it.
  double a = rad(azimuth_deg);
  return glm::dvec3(-std::cos(a), std::sin(a), 0.0);
}

glm::dvec3 Camera::up() const { return glm::normalize(glm::cross(right(), forward())); }

glm::mat3 Camera::view_rotation() const {
  glm::dvec3 r = right(), u = up(), b = -forward();
  // glm is column-major: m[col][row]. Rows are r, u, b.
  glm::mat3 m;
  for (int c = 0; c < 3; ++c) {
    m[c][0] = static_cast<float>(r[c]);
    m[c][1] = static_cast<float>(u[c]);
    m[c][2] = static_cast<float>(b[c]);
  }
  return m;
}

glm::mat4 Camera::projection(double aspect, double near_mm, double far_mm) const {
  if (orthographic) {
    double h = ortho_height / 2, w = h * aspect;
    return glm::mat4(glm::ortho(-w, w, -h, h, near_mm, far_mm));
  }
  return glm::mat4(glm::perspective(rad(fov_y_deg), aspect, near_mm, far_mm));
}

void Camera::frame(const glm::dvec3& lo, const glm::dvec3& hi, double aspect) {
  target = (lo + hi) * 0.5;
  double radius = std::max(1e-3, glm::length(hi - lo) * 0.5);
  double half_fov = rad(fov_y_deg) / 2;
  double fit = std::min(half_fov, std::atan(std::tan(half_fov) * aspect));
  distance = radius / std::sin(fit) * 1.02;
  ortho_height = 2 * radius * 1.02 / std::min(1.0, aspect);
}

std::optional<std::array<double, 2>> parse_view(const std::string& name) {
  struct Named {
    const char* name;
    double az, el;
  };
  static const Named views[] = {
      {"axial", 180, 90},    {"superior", 180, 90}, {"inferior", 0, -90},  {"sagittal", -90, 0},
      {"left", -90, 0},      {"right", 90, 0},    {"coronal", 0, 0},      {"anterior", 0, 0},
      {"posterior", 180, 0},
  };
  for (const Named& v : views)
    if (name == v.name) return std::array<double, 2>{v.az, v.el};
  auto comma = name.find(',');
  if (comma == std::string::npos) return std::nullopt;
  char* end = nullptr;
  double az = std::strtod(name.c_str(), &end);
  if (end != name.c_str() + comma) return std::nullopt;
  double el = std::strtod(name.c_str() + comma + 1, &end);
  if (*end != '\0' || !std::isfinite(az) || !std::isfinite(el)) return std::nullopt;
  return std::array<double, 2>{az, std::clamp(el, -90.0, 90.0)};
}

}  // namespace vxl
