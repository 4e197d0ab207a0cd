// The window's frame budget (voxview --frame-budget): while the camera moves, draw the finest level of
// detail (.vxl spec §5.12) whose measured cost fits the budget; at rest, the scene's own level (the finest
// the GPU memory budget allows, scene_detail.h). Costs are measured per level as frames are drawn; a level
// not measured yet is estimated from its nearest measured neighbour at 8x per level (the segments it
// draws), and from the first picture's cost while nothing else is measured. A frame's cost also depends on what else it
// draws and shares the machine with (FrameLoad): each load is measured apart, and a load not measured at a level is
// estimated first from another load's cost at that level, scaled by what the two loads cost at a level where both were
// measured, then from its own nearest measured level. Pure logic: testable without GL.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "format/vxl_file.h"
#include "format/vxl_levels.h"

namespace vxl::app {

// What a frame draws besides the context at its level, and what it shares the cores with.
struct FrameLoad {
  // The focus drawn at full detail from its copy beside the context (focus first): its own segments.
  bool focus = false;
  // A selection or a focus copy being made on other threads: on a machine with few cores (and a software
  // rasteriser) it takes time from the drawing.
  bool work_in_flight = false;

  std::size_t index() const { return (focus ? 1 : 0) + (work_in_flight ? 2 : 0); }
  static constexpr std::size_t kCount = 4;
};

class FrameBudget {
 public:
  // budget_ms <= 0: no budget (always the scene's level).
  FrameBudget(double budget_ms, std::uint32_t scene_level, std::uint32_t coarsest_level);

  // The level to draw a frame at under `load`; `moving`: the camera changed since the last frame.
  std::uint32_t level_for(bool moving, FrameLoad load = {}) const;
  // A frame drawn at `level` under `load` took `ms`.
  void record(std::uint32_t level, double ms, FrameLoad load = {});
  // The first picture took `ms` at `level`. It also paid what a renderer pays once (its shaders built, its
  // buffers first drawn from: on llvmpipe about as much as the drawing), so it is an estimate only until a frame
  // is measured: a level it put over the budget is tried again once a measured one puts it within.
  void record_first_picture(std::uint32_t level, double ms);
  // The estimated frame time at `level` under `load`; 0 when nothing has been measured nor a first picture drawn.
  double estimate_ms(std::uint32_t level, FrameLoad load = {}) const;

 private:
  using Costs = std::array<double, kMaxLevels>;  // per level; 0: not measured
  // From the nearest level measured under the same load; 0 when none was.
  static double estimate_from_levels(const Costs& costs, std::uint32_t level);
  // How much dearer `load` is than `other`, at the level nearest `level` where both were measured; 0: none.
  double load_ratio(std::size_t load, std::size_t other, std::uint32_t level) const;

  double budget_ms_;
  std::uint32_t scene_level_, coarsest_level_;
  std::array<Costs, FrameLoad::kCount> measured_ms_{};
  Costs first_picture_ms_{};
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
