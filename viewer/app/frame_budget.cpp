#include "viewer/app/frame_budget.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "viewer/render/scene_layout.h"

namespace vxl::app {

FrameBudget::FrameBudget(double budget_ms, std::uint32_t scene_level, std::uint32_t coarsest_level)
    : budget_ms_(budget_ms),
      scene_level_(std::min(scene_level, kMaxLevels - 1)),
      coarsest_level_(std::clamp(coarsest_level, scene_level_, kMaxLevels - 1)) {}

void FrameBudget::record(std::uint32_t level, double ms, FrameLoad load) {
  if (level < kMaxLevels && ms >= 0) measured_ms_[load.index()][level] = ms;
}

void FrameBudget::record_first_picture(std::uint32_t level, double ms) {
  if (level < kMaxLevels && ms >= 0) first_picture_ms_[level] = ms;
}

double FrameBudget::estimate_from_levels(const Costs& costs, std::uint32_t level) {
  if (costs[level] > 0) return costs[level];
  // The nearest measured level, scaled by the segments: 1/8 of them per level.
  for (std::uint32_t distance = 1; distance < kMaxLevels; ++distance)
    for (const int sign : {-1, 1}) {
      const int other = int(level) + sign * int(distance);
      if (other < 0 || other >= int(kMaxLevels) || costs[other] <= 0) continue;
      return costs[other] * std::pow(double(kLevelRatio), double(other - int(level)));
    }
  return 0;
}

double FrameBudget::load_ratio(std::size_t load, std::size_t other, std::uint32_t level) const {
  for (std::uint32_t distance = 0; distance < kMaxLevels; ++distance)
    for (const int sign : {-1, 1}) {
      const int l = int(level) + sign * int(distance);
      if (l < 0 || l >= int(kMaxLevels)) continue;
      if (measured_ms_[load][l] > 0 && measured_ms_[other][l] > 0)
        return measured_ms_[load][l] / measured_ms_[other][l];
    }
  return 0;
}

double FrameBudget::estimate_ms(std::uint32_t level, FrameLoad load) const {
  if (level >= kMaxLevels) return 0;
  const std::size_t own = load.index();
  if (measured_ms_[own][level] > 0) return measured_ms_[own][level];
  // The other loads, the nearest first (one difference before two).
  std::array<std::size_t, FrameLoad::kCount - 1> others{};
  std::size_t n = 0;
  for (const int differences : {1, 2})
    for (std::size_t other = 0; other < FrameLoad::kCount; ++other)
      if (std::popcount(other ^ own) == differences) others[n++] = other;
  // This level measured under another load, scaled by what the two loads cost where both were measured.
  for (const std::size_t other : others)
    if (const double ratio = load_ratio(own, other, level); ratio > 0 && measured_ms_[other][level] > 0)
      return measured_ms_[other][level] * ratio;
  if (const double ms = estimate_from_levels(measured_ms_[own], level); ms > 0) return ms;
  // Nothing under this load yet (the first frames of a selection), so no ratio is known either: another load's
  // estimate as it is; the next frame measures this one.
  for (const std::size_t other : others)
    if (const double ms = estimate_from_levels(measured_ms_[other], level); ms > 0) return ms;
  return estimate_from_levels(first_picture_ms_, level);
}

std::uint32_t FrameBudget::level_for(bool moving, FrameLoad load) const {
  if (!moving || budget_ms_ <= 0) return scene_level_;
  for (std::uint32_t level = scene_level_; level <= coarsest_level_; ++level) {
    const double ms = estimate_ms(level, load);
    if (ms <= budget_ms_) return level;  // unmeasured (0): try it
  }
  return coarsest_level_;
}

std::uint32_t first_picture_level(std::span<const std::uint64_t> segments, std::uint32_t scene_level) {
  if (segments.empty()) return scene_level;
  const auto coarsest = static_cast<std::uint32_t>(segments.size() - 1);
  for (std::uint32_t level = std::min(scene_level, coarsest); level <= coarsest; ++level)
    if (segments[level] <= kFirstPictureSegments) return level;
  return coarsest;
}

std::vector<std::uint64_t> level_segments(std::span<const VxlFile* const> files) {
  std::vector<std::uint64_t> segments(SceneLayout::coarsest_level(files) + 1, 0);
  for (const VxlFile* f : files)
    for (std::size_t i = 0; i < f->voxels().size(); ++i)
      for (std::uint32_t d = 0; d < segments.size(); ++d) segments[d] += f->level(i, d).segment_count;
  return segments;
}

}  // namespace vxl::app
