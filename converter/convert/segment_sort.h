// How one voxel's segments are sorted into an order (spec §5.5 ORDB): by key, ties by ascending block-local
// index, the indices written as packed entries. Used by VoxelOrderWriter (segment_orders.h).
#pragma once

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "format/vxl_positions.h"

namespace vxl::detail {

// Order-preserving map of a double (not NaN) to an unsigned integer: its sign and magnitude as a two's
// complement integer, offset by 2^63. Unlike flipping every bit of negative numbers, this keeps the zero
// low mantissa bits of a sum of two floats zero for both signs, so that the keys of a voxel that
// straddles 0 still vary in few enough bits for sort_segments to pack them with their index.
std::uint64_t sortable_bits(double d);

// A segment whose key varies in too many bits to share 64 bits with its index.
struct KeyedSegment {
  std::uint64_t key;
  std::uint32_t local;
};

// Per worker thread. Reserved for the largest voxel up front (keyed on first use), so that these never
// grow past it: sort_scratch_bytes() is a bound that callers budget with.
struct SortScratch {
  std::uint32_t max_vertices = 0;
  std::vector<std::uint64_t> keys, packed_tmp;  // keys: packed with the index in place where they fit
  std::vector<KeyedSegment> keyed, keyed_tmp;
  std::vector<std::uint16_t> bucket_keys;  // QuantumSumKeys' counting sort (reserved on first use)
  std::vector<std::uint32_t> bucketed;
  std::vector<std::uint32_t> counts;
};

// Writes the order of one voxel's segments (block-local `starts`, ascending) by ascending `s.keys`
// (which differ in the bits of `varying`), ties by ascending index, to `dst`; returns the end of what
// it wrote.
std::uint8_t* sort_segments(const std::vector<std::uint32_t>& starts, std::uint32_t vertex_count,
                            std::uint32_t entry_bits, std::uint64_t varying, SortScratch& s, std::uint8_t* dst);

// A packed block's keys along an axis, ranked without their 21-39 varying bits. The key of segment (a, b) is
// d[qa] + d[qb], d being what the axis's quanta decode to: nondecreasing in q and close to affine, a quantum
// many float ulps wide. So the sums of one quantum sum qa + qb (0..2046) fall in a narrow bucket, below those
// of the next: where the buckets are apart, (qa + qb, the key's offset in its bucket) ranks the segments as
// the key does, in 11 bits and a few. The largest voxels then sort in one radix pass instead of two to four
// (each a pass over main memory). Nothing rests on the model being right: the buckets' separation is checked
// once, and every key's place in its bucket as it is made (QuantumSumKeys::sort falls back when one is not).
class QuantumSumKeys {
 public:
  // From the axis's decoded quanta (PackedBlock::decoded).
  void prepare(const std::array<float, kPackedSteps + 1>& decoded);
  // Not prepared: sort returns nullptr.
  void clear() { usable_ = false; }
  // Whether the buckets are apart (sort may still find a key outside its bucket and return nullptr).
  bool usable() const { return usable_; }
  // Writes the order of the block's segments (block-local `starts`, ascending) by ascending key, ties by
  // ascending index, as sort_segments does, and returns the end of what it wrote; nullptr (nothing written)
  // where the shortcut does not hold.
  std::uint8_t* sort(const std::vector<std::uint32_t>& starts, const std::uint32_t* words, int axis,
                     std::uint32_t vertex_count, std::uint32_t entry_bits, SortScratch& s, std::uint8_t* dst) const;

 private:
  static constexpr std::uint32_t kSums = 2 * kPackedSteps + 1;
  static constexpr int kSumBits = std::bit_width(kSums - 1);
  static constexpr int kMaxOffsetBits = 5;  // beyond it the key's own bits sort about as fast
  static_assert(kSumBits + kMaxOffsetBits <= 16, "keys of a counting sort are 16-bit");
  static constexpr std::size_t kCountingSortItems = std::size_t(1) << 16;
  bool usable_ = false;
  int offset_bits_ = 0;
  std::uint64_t span_ = 0;                            // a bucket's keys lie in [floor_[s], floor_[s] + span_]
  std::array<std::int64_t, kPackedSteps + 1> units_;  // d[q] in units of the largest power of two dividing them all
  std::array<std::int64_t, kSums> floor_;             // by quantum sum: the least sum of units it may hold
};

// The most a SortScratch reserved for voxels of up to `max_vertices` vertices takes.
std::uint64_t sort_scratch_bytes(std::uint32_t max_vertices);

}  // namespace vxl::detail
