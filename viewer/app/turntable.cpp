#include "viewer/app/turntable.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace vxl::app {

Camera turntable_camera(const Camera& start, int frame, int frames) {
  Camera c = start;
  c.azimuth_deg = start.azimuth_deg + 360.0 * frame / frames;
  return c;
}

std::vector<glm::dvec3> turntable_points(std::span<const glm::dvec3> points, const glm::dvec3& pivot, int frames) {
  // The angles 360 i / N are their own negatives modulo 360, so turning the points either way gives the
  // same set as turning the camera.
  std::vector<glm::dvec3> out;
  out.reserve(points.size() * std::max(frames, 1));
  for (int i = 0; i < std::max(frames, 1); ++i) {
    const double a = 2.0 * 3.14159265358979323846 * i / std::max(frames, 1), ca = std::cos(a), sa = std::sin(a);
    for (const glm::dvec3& p : points) {
      const glm::dvec3 q = p - pivot;
      out.emplace_back(pivot.x + ca * q.x - sa * q.y, pivot.y + sa * q.x + ca * q.y, p.z);
    }
  }
  return out;
}

std::string turntable_frame_path(const std::string& png, int frame, int frames) {
  const std::filesystem::path p(png);
  int digits = 3;
  for (int n = frames - 1; n >= 1000; n /= 10) ++digits;
  char number[32];
  std::snprintf(number, sizeof number, "_%0*d", digits, frame);
  std::string ext = p.extension().string();
  if (ext.empty()) ext = ".png";
  return (p.parent_path() / (p.stem().string() + number + ext)).string();
}

}  // namespace vxl::app
