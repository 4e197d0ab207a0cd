// The window's default size on a given screen. Pure logic, testable without a display.
#pragma once

#include <algorithm>
#include <array>

namespace vxl::app {

// The share of the monitor's work area (the screen less task bars) a default window may cover: the rest
// leaves room for the title bar and the desktop around it.
inline constexpr double kWindowShareOfWorkArea = 0.9;

// `width` x `height`, scaled down with its aspect kept so that it fits `kWindowShareOfWorkArea` of a
// `area_width` x `area_height` work area; unchanged when it fits or when the area is unknown (0).
inline std::array<int, 2> fit_to_work_area(int width, int height, int area_width, int area_height) {
  if (area_width <= 0 || area_height <= 0) return {width, height};
  const double scale =
      std::min({1.0, kWindowShareOfWorkArea * area_width / width, kWindowShareOfWorkArea * area_height / height});
  return {std::max(1, int(width * scale)), std::max(1, int(height * scale))};
}

}  // namespace vxl::app
