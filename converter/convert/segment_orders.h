// Per-voxel segment orders (paper §"View-Dependent Line Order per Axis"; spec §5.5, §6.4).
//
// For each stored direction d, a voxel's segments (a, b) are sorted by dot(a + b, d) ascending, ties by
// block-local index, so the file is deterministic. Only one of d / −d is stored: the renderer reads the
// order backwards for −d.
//
// Order sets: `axis` and `axis+diag` share one direction set between all voxels (DIRS); `random:N`
// (paper §"Different sorting orders") gives every voxel its own N pseudo-random directions, uniform on the
// sphere and derived from (seed, voxel coordinate) alone, stored per voxel in VDIR (spec §5.10).
#pragma once

#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "converter/convert/voxelize.h"
#include "format/vxl_layout.h"
#include "format/vxl_levels.h"

namespace vxl {

// The seed of `random:N` sets made by `voxlines convert`. Any seed gives a valid file (the directions
// are stored); a fixed one makes conversions reproducible.
inline constexpr std::uint64_t kRandomOrderSeed = 0x566F786C696E6573ull;  // "Voxlines"

struct OrderSetSpec {
  OrderSet kind = OrderSet::Axis;
  std::string name = "axis";
  // The DIRS entries (unit vectors), K of them. A random set has no shared directions: it stores K
  // placeholders (1, 0, 0) there (spec §5.2) and each voxel's own in VDIR (voxel_directions below).
  std::vector<std::array<float, 3>> directions;
  std::uint64_t seed = kRandomOrderSeed;  // random sets only
  bool per_voxel() const { return kind == OrderSet::Random; }
};

// "axis" (K = 3: ±X, ±Y, ±Z), "axis+diag" (K = 7: also the 8 cube diagonals) or "random:N" (K = N,
// 1 <= N <= 64, per voxel). Throws vxl::Error (Usage) for anything else.
OrderSetSpec parse_order_set(const std::string& name);

// The DIRS entries of an order set.
std::vector<DirectionEntry> order_directions(const OrderSetSpec& set);

// The K directions voxel `coord` sorts by: the shared ones, or for a random set its own, a function of
// (set.seed, coord) only. `out` has K entries.
void voxel_directions(const OrderSetSpec& set, const std::int32_t (&coord)[3], std::span<std::array<float, 3>> out);

// The VDIR payload (voxels.size() x K entries, voxel-major) of a random set; nothing for other sets
// (`out` is then empty).
void fill_voxel_directions(const OrderSetSpec& set, std::span<const VoxelEntry> voxels, std::span<DirectionEntry> out);

// A voxel's level prefixes (its LODS entries, level_count - 1 of them) in a voxel-major LODS payload.
inline std::span<const LevelEntry> level_row(std::span<const LevelEntry> levels, std::size_t voxel,
                                             std::uint32_t level_count) {
  return levels.subspan(voxel * (level_count - 1), level_count - 1);
}

// Sets every voxel's flags (order entry width) and order_offset for K = `stored_orders` and every level
// of `levels` (voxel_count x (level_count - 1)); returns the size of the ORDB payload, so that it can be
// allocated before the orders are built.
std::uint64_t layout_orders(std::span<VoxelEntry> voxels, std::span<const LevelEntry> levels, std::uint32_t level_count,
                            std::uint32_t stored_orders);

// Writes one voxel's orders at a time, for callers that do other per-voxel work in the same pass (the
// unpacker computes the voxel's tight bounds while its vertices are in cache). It keeps its sort
// buffers between voxels: use one per thread.
class VoxelOrderWriter {
 public:
  // `set` must outlive the writer (it is not copied). `max_vertices`: the largest voxel this writer will
  // see, so that its buffers are reserved once and never grow past order_scratch_bytes(max_vertices); 0
  // lets them grow as needed.
  explicit VoxelOrderWriter(const OrderSetSpec& set, std::uint32_t max_vertices = 0);
  ~VoxelOrderWriter();
  VoxelOrderWriter(VoxelOrderWriter&&) noexcept;

  // Sorts voxel `v`'s segments (the vertices of its block that do not end a voxline in `ends`) for every
  // direction of the set and writes its K orders at `dst` (the ORDB payload plus v.order_offset; the
  // voxel's flags and order_offset as layout_orders set them), then those of each coarser level in `row`
  // (its LODS entries) after them. Every byte of the voxel's orders is written, the padding (zero)
  // included, so `dst` need not be cleared.
  void write(const VoxelEntry& v, std::span<const LevelEntry> row, std::span<const float> vertices,
             const VoxlineEnds& ends, std::uint8_t* dst);
  // The same from the voxel's packed block (v.vertex_count words, spec §5.4; the end bits inside): the
  // orders of the positions the words decode to, without decoding the block.
  void write_packed(const VoxelEntry& v, std::span<const LevelEntry> row, const std::uint32_t* words,
                    std::uint8_t* dst);

 private:
  void use_directions_of(const VoxelEntry& v);
  // Every level's orders of v's block, read through `block` (FloatBlock, PackedBlock or DecodedPackedBlock in the
  // .cpp).
  template <typename Block>
  void write_levels(const VoxelEntry& v, std::span<const LevelEntry> row, const Block& block, std::uint8_t* dst);
  // The K orders of the first `level.vertex_count` vertices of the block; returns the end of what it wrote.
  template <typename Block>
  std::uint8_t* write_level(const LevelEntry& level, const Block& block, std::uint8_t* dst);

  struct Scratch;
  const OrderSetSpec* set_;
  bool have_directions_ = false;  // a shared set is looked up once; a per-voxel set for every voxel
  std::vector<std::array<float, 3>> directions_;
  std::vector<int> axis_of_;  // the component of an axis direction, -1 for any other
  std::unique_ptr<Scratch> scratch_;
};

// An upper bound of what a VoxelOrderWriter allocates (its sort buffers, growth
// included) when no voxel has more than `max_vertices` vertices, for callers that budget memory.
std::uint64_t order_scratch_bytes(std::uint32_t max_vertices);

}  // namespace vxl
