// What the voxelisation (Algorithm 1 of the Voxlines paper, Osman et al., with the splitting of steps longer
// than a voxel at voxel faces: spec §6.3; voxelize_streamline.h) shares with the stages around it: the
// progress callback, the guard against a voxel size far below the steps, the voxline-end bits the orders
// read, and a point's voxel coordinate.
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "format/base/parallel.h"

namespace vxl {

// Called with a stage name and a fraction in [0, 1] of that stage; may be empty.
using ProgressFn = std::function<void(const char* stage, double fraction)>;

// A conversion is refused (with a suggested voxel size) when splitting long steps would add more than this
// many points per source point (and 4096 more, so that a small file of a few long steps converts): a guard
// against a voxel size far below the step length.
inline constexpr double kMaxSyntheticPerPoint = 1.0;

// One bit per vertex, set when the vertex is the last of its voxline, so that no segment starts there
// (spec §6.2). The orders find a block's segments with it. A bit, not a byte, per vertex: it is
// read once per vertex and order, and 8 times smaller.
class VoxlineEnds {
 public:
  VoxlineEnds() = default;
  explicit VoxlineEnds(std::uint64_t vertex_count) : words_((vertex_count + 63) / 64, 0) {}
  // No end among `vertex_count` vertices, in the memory held already where it is enough.
  void reset(std::uint64_t vertex_count) { words_.assign((vertex_count + 63) / 64, 0); }
  bool test(std::uint64_t vertex) const { return (words_[vertex >> 6] >> (vertex & 63)) & 1u; }
  // Atomic: the blocks of two threads can meet inside one word.
  void set(std::uint64_t vertex) {
    const std::uint64_t bit = 1ull << (vertex & 63);
#if defined(__cpp_lib_atomic_ref)
    std::atomic_ref<std::uint64_t>(words_[vertex >> 6]).fetch_or(bit, std::memory_order_relaxed);
#else  // a C++ library without atomic_ref: the web viewer's, whose build runs one thread
    static_assert(!kThreadsAvailable);
    words_[vertex >> 6] |= bit;
#endif
  }

 private:
  std::vector<std::uint64_t> words_;
};

// The integer voxel coordinate of a point (spec §6.1), exposed for tests.
inline std::int64_t voxel_coordinate(float p, double origin, double voxel_size) {
  return static_cast<std::int64_t>(std::floor((static_cast<double>(p) - origin) / voxel_size));
}

}  // namespace vxl
