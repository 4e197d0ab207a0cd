// Voxelisation: Algorithm 1 of the Voxlines paper (Osman et al.), plus the splitting of steps longer
// than a voxel at voxel faces (spec §6.3), and the per-voxel vertex blocks of spec §5.3–§5.7.
//
//   streamlines --(voxel of each point, §6.1)--> voxlines --(grouped per voxel)--> vertex blocks
//
// Two passes, so that the output can be sized before it is written: plan_voxels finds the voxlines and
// the voxel table (every count and size), place_vertices then writes the blocks and tables into spans
// the caller provides (the mapped output file, in convert_tractogram). voxelize() runs both into vectors.
//
// Work is split over threads by contiguous streamline ranges; the result does not depend on the thread
// count (voxlines keep streamline order inside each block).
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "converter/tractogram.h"
#include "format/base/parallel.h"  // resolve_threads: the meaning of VoxelizeSettings::threads
#include "format/vxl_layout.h"
#include "format/vxl_levels.h"

namespace vxl {

// Called with a stage name and a fraction in [0, 1] of that stage; may be empty.
using ProgressFn = std::function<void(const char* stage, double fraction)>;

struct VoxelizeSettings {
  double voxel_size = 10.0;  // mm
  unsigned threads = 0;      // 0: all hardware threads
  // Levels of detail (vxl_levels.h, spec §5.12), 1 .. kMaxLevels: 1 keeps every block in streamline order.
  std::uint32_t levels = 1;
  ProgressFn progress;
  // Refuse (with a suggested voxel size) when splitting long steps would add more than this many
  // points per source point: a guard against a voxel size far below the step length.
  double max_synthetic_per_point = 1.0;
  // Packed positions (spec §5.4): pass 1 also finds each voxel's tight bounds, so that place_vertices packs
  // every vertex as it places it (into VoxelBlocks::packed_vertices; no float copy of the blocks is held).
  bool pack_positions = false;
};

// One bit per vertex, set when the vertex is the last of its voxline, so that no segment starts there
// (spec §6.2). build_orders finds a block's segments with it. A bit, not a byte, per vertex: it is
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
    std::atomic_ref<std::uint64_t>(words_[vertex >> 6]).fetch_or(1ull << (vertex & 63), std::memory_order_relaxed);
  }

 private:
  std::vector<std::uint64_t> words_;
};

// The voxel blocks, without orders (build_orders adds those), in memory.
struct VoxelizedTractogram {
  MetaSection meta{};
  std::vector<VoxelEntry> voxels;                       // sorted by (z, y, x); order_offset/flags set by build_orders
  std::vector<LevelEntry> levels;                       // LODS: voxel_count x (level_count - 1)
  std::vector<float> vertices;                          // 3 * vertex_count
  std::vector<VoxlineEntry> voxlines;                   // streamline order
  std::vector<std::uint64_t> streamline_first_voxline;  // N + 1
  VoxlineEnds voxline_ends;
};

// Where place_vertices writes; each span has exactly the size the plan's meta gives.
struct VoxelBlocks {
  std::span<VoxelEntry> voxels;                       // voxel_count
  std::span<LevelEntry> levels;                       // voxel_count x (level_count - 1)
  std::span<float> vertices;                          // 3 * vertex_count; empty when packing
  std::span<VoxlineEntry> voxlines;                   // voxline_count
  std::span<std::uint64_t> streamline_first_voxline;  // streamline_count + 1
  // One per point value set of the tractogram, vertex_count each: the values spread like the positions
  // (spec §5.11). Empty when the tractogram has none.
  std::vector<std::span<float>> vertex_values;
  std::span<std::uint32_t> packed_vertices;  // vertex_count when packing (then `vertices` is empty), else empty
};

// The result of pass 1: every streamline's voxlines and the voxel table.
class VoxelPlan {
 public:
  VoxelPlan(VoxelPlan&&) noexcept;
  VoxelPlan& operator=(VoxelPlan&&) noexcept;
  ~VoxelPlan();

  // Counts, grid and bounds; stored_order_count and order_set are left to the caller.
  const MetaSection& meta() const { return meta_; }
  // Sorted by (z, y, x), with coord, vertex_first, vertex_count and segment_count set. The caller may
  // set flags and order_offset (layout_orders); place_vertices copies the entries and adds tight bounds.
  std::span<VoxelEntry> voxels() { return voxels_; }
  // The level prefixes of each voxel (spec §5.12), voxel-major.
  std::span<const LevelEntry> levels() const { return levels_; }
  // Each streamline's length (SLEN, spec §5.15), measured by the bounds scan from the source points.
  std::span<const float> streamline_lengths() const { return lengths_; }

 private:
  struct Work;  // the per-thread voxlines (voxelize.cpp)
  VoxelPlan();
  friend VoxelPlan plan_voxels(const Tractogram& tractogram, const VoxelizeSettings& settings);
  friend VoxlineEnds place_vertices(VoxelPlan&& plan, Tractogram&& tractogram, const VoxelBlocks& out);

  std::unique_ptr<Work> work_;
  MetaSection meta_{};
  std::vector<VoxelEntry> voxels_;
  std::vector<LevelEntry> levels_;
  std::vector<float> lengths_;
};

// Pass 1. Throws vxl::Error: Input for a non-finite coordinate, Unsupported (with a suggestion) when a
// limit of spec §9 would be exceeded.
VoxelPlan plan_voxels(const Tractogram& tractogram, const VoxelizeSettings& settings);

// Pass 2: writes the voxel table (with tight bounds), the vertex blocks, their values and the voxline and
// streamline tables into `out`, and releases the tractogram's positions and point values (the blocks then hold every
// point, so peak memory stays bounded). Returns the voxline ends of the blocks, for build_orders.
VoxlineEnds place_vertices(VoxelPlan&& plan, Tractogram&& tractogram, const VoxelBlocks& out);

// Both passes, into vectors. Consumes the tractogram's positions like place_vertices.
VoxelizedTractogram voxelize(Tractogram&& tractogram, const VoxelizeSettings& settings);

// The integer voxel coordinate of a point (spec §6.1), exposed for tests.
inline std::int64_t voxel_coordinate(float p, double origin, double voxel_size) {
  return static_cast<std::int64_t>(std::floor((static_cast<double>(p) - origin) / voxel_size));
}

}  // namespace vxl
