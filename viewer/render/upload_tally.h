// What the scenes of one context copied to the GPU, and for how long (voxview --stats): the bytes of every span made
// resident, and the time spans were being filled (on other threads) and handed to the driver. Two spans fill at once,
// and they may end in either order: the union of their times is counted, so that time during which both filled
// counts once and bytes / seconds is the rate a user waits on. The time a finished fill waits for the window's next
// look at it is not counted. (Without threads, in a web page, a span is made a part a call: its time runs from its
// first part to its last, the frames between included.)
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <utility>
#include <vector>

namespace vxl {

class UploadTally {
 public:
  using Clock = std::chrono::steady_clock;

  // A span of `bytes` was uploaded from `begin` to `end` (or only its per-vertex buffers, made again).
  void add(std::uint64_t bytes, Clock::time_point begin, Clock::time_point end) {
    bytes_ += bytes;
    ++spans_;
    if (end <= begin) return;
    // The busy intervals that meet [begin, end] are merged with it into one.
    auto first = std::lower_bound(busy_.begin(), busy_.end(), begin,
                                  [](const Interval& i, Clock::time_point t) { return i.second < t; });
    auto last = first;
    Clock::duration covered{};
    while (last != busy_.end() && last->first <= end) {
      begin = std::min(begin, last->first);
      end = std::max(end, last->second);
      covered += last->second - last->first;
      ++last;
    }
    seconds_ += std::chrono::duration<double>((end - begin) - covered).count();
    busy_.insert(busy_.erase(first, last), Interval{begin, end});
  }

  std::uint64_t bytes() const { return bytes_; }
  std::uint64_t spans() const { return spans_; }  // uploads: a span uploaded again counts again
  double seconds() const { return seconds_; }
  // Gigabytes (10^9 bytes) a second; 0 before anything was uploaded.
  double gb_per_s() const { return seconds_ > 0 ? double(bytes_) / 1e9 / seconds_ : 0; }

 private:
  using Interval = std::pair<Clock::time_point, Clock::time_point>;
  std::uint64_t bytes_ = 0, spans_ = 0;
  double seconds_ = 0;
  std::vector<Interval> busy_;  // disjoint, in order: when uploads were running (16 bytes an idle gap between them)
};

}  // namespace vxl
