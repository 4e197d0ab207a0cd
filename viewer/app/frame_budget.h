// The window's frame budget (voxview --frame-budget): while the camera moves, draw the finest level of
// detail (.vxl spec §5.12) whose measured cost fits the budget; at rest, the scene's own level (the finest
// the GPU memory budget allows, scene_detail.h). Costs are measured per level as frames are drawn; a level
// not measured yet is estimated from its nearest measured neighbour at 8x per level (the segments it
// draws). Pure logic: testable without GL.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "format/vxl_file.h"
#include "format/vxl_levels.h"

namespace vxl::app {

class FrameBudget {
 public:
  // budget_ms <= 0: no budget (always the scene's level).
  FrameBudget(double budget_ms, std::uint32_t scene_level, std::uint32_t coarsest_level);

  // The level to draw a frame at; `moving`: the camera changed since the last frame.
  std::uint32_t level_for(bool moving) const;
  // A frame drawn at `level` took `ms`.
  void record(std::uint32_t level, double ms);
  // The estimated frame time at `level`; 0 when nothing has been measured.
  double estimate_ms(std::uint32_t level) const;

 private:
  double budget_ms_;
  std::uint32_t scene_level_, coarsest_level_;
  std::array<double, kMaxLevels> measured_ms_{};  // 0: not measured
};

// The window's first picture comes before the scene's level is uploaded: the finest level, from the scene's
// level down, that draws at most this many segments. Why 250k: Mesa llvmpipe draws 0.4-2.5M segments a
// second at 1280x800 on two cores (busy to quiet), and the first picture must reach the screen within a
// second of the process starting, of which loading the program and opening the window take 0.3-0.8 s;
// a GPU draws it at once.
inline constexpr std::uint64_t kFirstPictureSegments = 250'000;

// `segments[d]`: the scene's segments at level d (up to the coarsest level).
std::uint32_t first_picture_level(std::span<const std::uint64_t> segments, std::uint32_t scene_level);
// The files' segments at each level, up to the coarsest all of them have (first_picture_level's `segments`).
std::vector<std::uint64_t> level_segments(std::span<const VxlFile* const> files);

}  // namespace vxl::app
