#include "viewer/render/camera.h"

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

namespace {

// The distance, target and ortho_height that fit `points`, with the target at `pivot` when given.
void fit_points(Camera& c, std::span<const glm::dvec3> points, double aspect, const std::optional<glm::dvec3>& pivot) {
  const glm::dvec3 r = c.right(), u = c.up(), b = -c.forward();
  // Coordinates relative to a point inside the set (its bounds' centre), for precision far from the origin.
  glm::dvec3 lo(0.0), hi(0.0);
  if (!points.empty()) lo = hi = points[0];
  for (const glm::dvec3& p : points) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const glm::dvec3 origin = pivot.value_or((lo + hi) * 0.5);
  const double scale = 1.0 + Camera::kFrameMargin;
  const double ty = std::tan(rad(c.fov_y_deg) / 2) / scale, tx = ty * aspect;
  double x_lo = HUGE_VAL, x_hi = -HUGE_VAL, y_lo = HUGE_VAL, y_hi = -HUGE_VAL, z_lo = HUGE_VAL, z_hi = -HUGE_VAL;
  // Perspective: the eye at (ex, ey, ez) in (r, u, b) sees point (x, y, z) when |x - ex| <= tx (ez - z) and
  // likewise for y: ex + tx ez >= x + tx z and -ex + tx ez >= -x + tx z. The least ez meeting both sets
  // of constraints is (A + B) / (2 tx) with A, B the right sides' maxima, at ex = (A - B) / 2.
  double a = -HUGE_VAL, bb = -HUGE_VAL, cc = -HUGE_VAL, d = -HUGE_VAL, ez_about = -HUGE_VAL;
  for (const glm::dvec3& p : points) {
    const glm::dvec3 q = p - origin;
    const double x = glm::dot(q, r), y = glm::dot(q, u), z = glm::dot(q, b);
    x_lo = std::min(x_lo, x), x_hi = std::max(x_hi, x);
    y_lo = std::min(y_lo, y), y_hi = std::max(y_hi, y);
    z_lo = std::min(z_lo, z), z_hi = std::max(z_hi, z);
    a = std::max(a, x + tx * z), bb = std::max(bb, -x + tx * z);
    cc = std::max(cc, y + ty * z), d = std::max(d, -y + ty * z);
    ez_about = std::max(ez_about, z + std::max(std::abs(x) / tx, std::abs(y) / ty));
  }
  if (points.empty()) a = bb = cc = d = ez_about = x_lo = x_hi = y_lo = y_hi = z_lo = z_hi = 0;
  const double tan_half = std::tan(rad(c.fov_y_deg) / 2);
  if (c.orthographic) {
    const double half_w = pivot ? std::max(std::abs(x_lo), std::abs(x_hi)) : (x_hi - x_lo) / 2;
    const double half_h = pivot ? std::max(std::abs(y_lo), std::abs(y_hi)) : (y_hi - y_lo) / 2;
    c.ortho_height = std::max(1e-3, 2 * std::max(half_h, half_w / aspect) * scale);
    c.target = pivot ? origin : origin + r * ((x_lo + x_hi) / 2) + u * ((y_lo + y_hi) / 2) + b * ((z_lo + z_hi) / 2);
    // As the camera controller converts between the projections: the same size at the target.
    c.distance = c.ortho_height / (2 * tan_half);
    return;
  }
  if (pivot) {
    c.target = origin;
    c.distance = std::max(1e-3, ez_about);
  } else {
    const double ez = std::max((a + bb) / (2 * tx), (cc + d) / (2 * ty));
    const double zc = (z_lo + z_hi) / 2;
    c.target = origin + r * ((a - bb) / 2) + u * ((cc - d) / 2) + b * zc;
    c.distance = std::max(1e-3, ez - zc);
  }
  c.ortho_height = 2 * c.distance * tan_half;
}

}  // namespace

void Camera::frame_points(std::span<const glm::dvec3> points, double aspect) {
  fit_points(*this, points, aspect, std::nullopt);
}

void Camera::frame_points_about(std::span<const glm::dvec3> points, const glm::dvec3& pivot, double aspect) {
  fit_points(*this, points, aspect, pivot);
}

namespace {

// The standard views, in one table for parse_view and the texts that list them.
struct NamedView {
  const char* name;
  const char* alias;  // the same view's other name, or null
  double az, el;
};
constexpr NamedView kViews[] = {
    {"axial", "superior", 180, 90}, {"inferior", nullptr, 0, -90}, {"sagittal", "left", -90, 0},
    {"right", nullptr, 90, 0},      {"coronal", "anterior", 0, 0}, {"posterior", nullptr, 180, 0},
};

}  // namespace

std::string view_names_text() {
  std::string text;
  for (const NamedView& v : kViews)
    text += (text.empty() ? "" : ", ") + std::string(v.name) + (v.alias ? " (" + std::string(v.alias) + ")" : "");
  return text;
}

std::optional<std::array<double, 2>> parse_view(const std::string& name) {
  for (const NamedView& v : kViews)
    if (name == v.name || (v.alias && name == v.alias)) return std::array<double, 2>{v.az, v.el};
  auto comma = name.find(',');
  if (comma == std::string::npos) return std::nullopt;
  char* end = nullptr;
  double az = std::strtod(name.c_str(), &end);
  if (end != name.c_str() + comma) return std::nullopt;
  double el = std::strtod(name.c_str() + comma + 1, &end);
  if (*end != '\0' || !std::isfinite(az) || !std::isfinite(el) || std::abs(az) > ViewLimits::kMaxAzimuthDeg)
    return std::nullopt;
  return std::array<double, 2>{az, std::clamp(el, -90.0, 90.0)};
}

}  // namespace vxl
