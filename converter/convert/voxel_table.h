// The stages of voxelisation that both conversion paths run — voxelize.cpp over a tractogram in memory
// (split over threads by streamline range) and streaming_convert.cpp over batches read from a file in
// bounded memory — so that both make exactly the same bytes:
//
//   BoundsScan          bounds, finiteness and longest step of the points         (before the grid is set)
//   set_grid            the grid of spec §6.1 over those bounds
//   voxelize_streamline the voxlines of one streamline (voxelize_streamline.h)
//   count_voxel_use     the vertices and segments those voxlines add to their voxels
//   build_voxel_table   the voxel table sorted by (z, y, x), from one or more local voxel indexes
//   place_voxline       a voxline's vertices into its block
//   set_tight_bounds    each voxel's bounds from its block
//
// Internal to the converter: the public interfaces are voxelize.h and streaming_convert.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "converter/convert/voxelize_streamline.h"
#include "format/vxl_layout.h"
#include "format/vxl_levels.h"

namespace vxl::detail {

// Bounds, the first non-finite point and the longest step of the streamlines seen so far. Scans stop at
// the first non-finite point (the conversion then fails on it); merging keeps the earliest.
struct BoundsScan {
  static constexpr std::uint64_t kNone = std::numeric_limits<std::uint64_t>::max();
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double longest_step2 = 0;
  // Sum of squared steps in 1/1024 mm^2 (each capped at 1 m^2: no overflow below 2^34 steps) and their
  // count, for the RMS step. Integers,
  // so that the sum does not depend on how streamlines are split over threads or batches.
  std::uint64_t step2_sum_fixed = 0, steps = 0;
  std::uint64_t bad_streamline = kNone, bad_point = 0;  // the first non-finite point

  // Streamlines [first, end) of `offsets` (points xyz in `pts`), numbered from `index_base` in messages.
  // With `lengths`, also stores streamline k's length (stored_length_of, format/streamline_length.h) at
  // lengths[k] for each streamline scanned.
  void add(const float* pts, const std::uint64_t* offsets, std::uint64_t first, std::uint64_t end,
           std::uint64_t index_base, float* lengths = nullptr);
  // Folds in a scan of later streamlines.
  void merge(const BoundsScan& later);
  // Throws Input for the first non-finite point, if any.
  void check(const std::string& path) const;
  double rms_step() const { return steps ? std::sqrt(double(step2_sum_fixed) / 1024.0 / double(steps)) : 0.0; }
};

// Vertex and segment counts per voxel of one local voxel index, and per streamline depth (vxl_levels.h):
// entry local_id * levels + depth.
struct VoxelUse {
  std::uint32_t levels = 1;
  std::vector<std::uint64_t> vertices, segments;
  explicit VoxelUse(std::uint32_t level_count = 1) : levels(level_count) {}
  void grow_to(std::size_t voxels) {
    if (vertices.size() < voxels * levels) {
      vertices.resize(voxels * levels, 0);
      segments.resize(voxels * levels, 0);
    }
  }
};

// Adds one streamline's voxlines (all of them, in order) to `use`, at the streamline's depth: each
// voxline's own points plus, but for the last, the connecting vertex. Throws Unsupported for a voxline
// longer than spec §9 allows.
void count_voxel_use(std::span<const TempVoxline> streamline, std::uint32_t depth, VoxelUse& use,
                     const std::string& path);

// One local voxel index (a thread's or the whole source's) and what build_voxel_table gives back for it.
struct LocalVoxels {
  const std::vector<Coord>* coords = nullptr;  // by local id
  const VoxelUse* use = nullptr;               // by local id
  std::vector<std::uint32_t> global_id;        // out: local id -> voxel index
  // out: (local id * levels + depth) -> the first vertex of its block this index places for streamlines
  // of that depth (after the deeper ones' and after the indexes before it)
  std::vector<std::uint64_t> cursor;
};

struct VoxelTable {
  std::vector<VoxelEntry> voxels;
  std::vector<LevelEntry> levels;  // the LODS payload: voxel_count x (level_count - 1); empty for one level
};

// The voxel table of spec §5.3, sorted by (z, y, x), with coord, vertex_first, vertex_count and
// segment_count set, and the level prefixes of spec §5.12 (the indexes' VoxelUse have `level_count`
// depths); inside each block the deeper streamlines' voxlines come first and the indexes place theirs in
// the order given (so that streamline order is kept within a depth). Sets m's voxel_count, vertex_count,
// segment_count and level_count. Throws Unsupported beyond the limits of spec §9.
VoxelTable build_voxel_table(std::span<LocalVoxels> indexes, std::uint32_t level_count, MetaSection& m,
                             const std::string& path);

// Calls run(xyz, count) for the runs of voxline j's vertices in block order: its optional synthetic first
// point, its own points and, but for the streamline's last voxline, the next voxline's first point.
template <typename Run>
void for_each_voxline_run(std::span<const TempVoxline> streamline, std::size_t j, const float* pts,
                          const float* synthetic_xyz, Run&& run) {
  const TempVoxline& v = streamline[j];
  auto first_point = [&](const TempVoxline& x) {
    return x.synthetic != kNoSynthetic ? synthetic_xyz + 3 * x.synthetic : pts + 3 * x.src_first;
  };
  if (v.synthetic != kNoSynthetic) run(first_point(v), std::uint64_t{1});
  run(pts + 3 * v.src_first, std::uint64_t{v.src_count});
  if (j + 1 < streamline.size()) run(first_point(streamline[j + 1]), std::uint64_t{1});
}

// Writes voxline j of one streamline's list (for_each_voxline_run's vertices) at `dst`; returns the
// vertices written.
inline std::uint64_t place_voxline(std::span<const TempVoxline> streamline, std::size_t j, const float* pts,
                                   const float* synthetic_xyz, float* dst) {
  float* out = dst;
  for_each_voxline_run(streamline, j, pts, synthetic_xyz,
                       [&](const float* xyz, std::uint64_t count) { out = std::copy_n(xyz, 3 * count, out); });
  return static_cast<std::uint64_t>(out - dst) / 3;
}

// The checks, shared so that both paths refuse the same input with the same message. All throw vxl::Error.
void check_voxel_size(double voxel_size, const std::string& path);      // Usage unless finite and > 0
void check_level_count(std::uint32_t levels, const std::string& path);  // Usage unless 1 .. kMaxLevels
// Sets the grid and bounds of `m` (voxel_size already set) for points inside [lo, hi]; Unsupported when
// an axis would have 2^31 cells or more.
Grid set_grid(MetaSection& m, const double lo[3], const double hi[3], const std::string& path);
[[noreturn]] void fail_too_many_synthetic(const std::string& path, double voxel_size, double longest_step2,
                                          std::uint64_t synthetic_limit);

// Each voxel's tight bounds from its block; `vertices` holds the blocks from vertex `vertex_base` on.
// A zero bound is stored as +0 whichever zero came first, so that the bounds do not depend on the order
// the vertices are seen in (VoxelBounds sees them in streamline order).
void set_tight_bounds(std::span<VoxelEntry> voxels, const float* vertices, std::uint64_t vertex_base);

// The tight bounds of each voxel of a local index, widened voxline by voxline while the voxlines are
// counted: the streaming conversion knows them before it places a vertex, so that it can pack each vertex
// as it places it (and hold 4 bytes a vertex instead of 12). Gives what set_tight_bounds gives.
class VoxelBounds {
 public:
  static constexpr std::uint64_t kBytesPerVoxel = 6 * sizeof(float);
  void grow_to(std::size_t voxels);
  // Widens the bounds of voxline j's voxel to the vertices place_voxline writes for it.
  void add_voxline(std::span<const TempVoxline> streamline, std::size_t j, const float* pts,
                   const float* synthetic_xyz);
  void set_tight_bounds(std::uint32_t local, VoxelEntry& v) const;
  // Widens the bounds of `local` to those of `other_local` in another index's bounds.
  void merge(std::uint32_t local, const VoxelBounds& other, std::uint32_t other_local);

 private:
  void add(std::uint32_t local, const float* xyz, std::uint64_t count);
  std::vector<float> lo_, hi_;  // 3 per local id
};

}  // namespace vxl::detail
