#include "turntable.h"

#include <cstdio>
#include <filesystem>

namespace vxl::app {

Camera turntable_camera(const Camera& start, int frame, int frames) {
  Camera c = start;
  c.azimuth_deg = start.azimuth_deg + 360.0 * frame / frames;
  return c;
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
