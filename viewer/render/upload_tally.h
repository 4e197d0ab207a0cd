// What the scenes of one context copied to the GPU, and for how long (voxview --stats, render_bench): the bytes
// of every span made resident, and the time spans were being filled (on other threads) and handed to the driver.
// Two spans fill at once: time during which both did is counted once, so bytes / seconds is the rate a user
// waits on. The time a finished fill waits for the window's next look at it is not counted.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>

namespace vxl {

class UploadTally {
 public:
  using Clock = std::chrono::steady_clock;

  // A span of `bytes` was uploaded from `begin` to `end` (or only its per-vertex buffers, made again).
  void add(std::uint64_t bytes, Clock::time_point begin, Clock::time_point end) {
    bytes_ += bytes;
    ++spans_;
    // Spans are added about in the order they began, so counting only what lies past the latest end so far
    // counts overlapping fills once.
    const Clock::time_point from = std::max(begin, busy_until_);
    if (end > from) seconds_ += std::chrono::duration<double>(end - from).count();
    busy_until_ = std::max(busy_until_, end);
  }

  std::uint64_t bytes() const { return bytes_; }
  std::uint64_t spans() const { return spans_; }  // uploads: a span uploaded again counts again
  double seconds() const { return seconds_; }
  // Gigabytes (10^9 bytes) a second; 0 before anything was uploaded.
  double gb_per_s() const { return seconds_ > 0 ? double(bytes_) / 1e9 / seconds_ : 0; }

 private:
  std::uint64_t bytes_ = 0, spans_ = 0;
  double seconds_ = 0;
  Clock::time_point busy_until_{};
};

}  // namespace vxl
