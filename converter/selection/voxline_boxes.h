// What one selection learns about the voxels it touches, kept for the next: each voxel's voxlines placed in its
// block (place_voxel_voxlines) with the box of the points a region test reads, in the block's packed quanta
// (spec §5.4). A region dragged through the window asks for a selection every frame, and consecutive positions
// touch mostly the same voxels: with their voxlines boxed, a voxline whose box misses a region is passed over and
// one whose box the region holds is kept, both without reading its points; only voxlines across a region's
// surface are tested point by point. The boxes hold for any region and any position, so nothing is invalidated as
// regions move. For one sphere (the first among the includes and excludes: the one a drag moves) each voxline also
// keeps how far its nearest point lies from the centre it was last measured from: moved by d since, the sphere can
// only have crossed the voxlines whose distance was within d of its radius, and only those are measured again.
// Packed files only (a float32 file's selections take the plain path).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "format/voxel_voxlines.h"
#include "format/vxl_file.h"
#include "format/vxl_positions.h"

namespace vxl {

// One voxline of a voxel, placed and boxed.
struct BoxedVoxline {
  static constexpr std::uint8_t kSyntheticFirst = 1, kFirstOfStreamline = 2, kLastOfStreamline = 4;
  std::uint32_t streamline = 0;
  std::uint32_t first = 0;  // its first vertex, counted from the voxel's first
  std::uint32_t own = 0;    // its own points (spec §5.6)
  std::uint8_t flags = 0;
  // The quanta of the points a region test reads (own points but a synthetic first): lo > hi on an axis when none.
  std::array<std::uint16_t, 3> lo{}, hi{};
  // The point that was the nearest when its distances were last measured, as its packed word's quanta (kNoNearest:
  // unknown): still inside the moved sphere, it decides the voxline without the others. Kept here rather than as
  // its place in the block: a drag tests it for a quarter of the voxlines it looks at, and a read in the block is a
  // cache miss for each.
  static constexpr std::uint32_t kQuantaBits = kPackedAxisMask | kPackedAxisMask << 10 | kPackedAxisMask << 20;
  static constexpr std::uint32_t kNoNearest = 0xFFFFFFFFu;  // not a word's quanta: bits 30 and 31 set
  std::uint32_t nearest_word = kNoNearest;
  // Where the nearest of those points lies from the voxel's reference centre (VoxelReference), in mm: a dragged
  // sphere moved by d from there has it within [near_lo - d, near_hi + d], which decides most voxlines without
  // their points. Unknown: [0, infinity].
  float near_lo = 0, near_hi = 0;
};

// The centre a voxel's near_lo / near_hi are measured from, when `known`.
struct VoxelReference {
  std::array<float, 3> centre{};
  bool known = false;
};

static_assert(sizeof(BoxedVoxline) == 40, "the budget counts 40 bytes a voxline");

class VoxlineBoxes {
 public:
  // What the boxes may take in all (40 bytes a voxline: 6.7M voxlines). A selection reads the voxels it finds no room
  // for without boxes; past half of it, those the last selection did not use are let go.
  static constexpr std::uint64_t kDefaultBudgetBytes = 256ull << 20;

  explicit VoxlineBoxes(const VxlFile& file, std::uint64_t budget_bytes = kDefaultBudgetBytes);
  VoxlineBoxes(const VoxlineBoxes&) = delete;
  VoxlineBoxes& operator=(const VoxlineBoxes&) = delete;

  // Voxel `voxel`'s voxlines, boxed on first use (placed through `index`, the file's, and its words read once);
  // nullopt when boxing them would take the boxes past the budget or the selection past what it may box
  // (selection_started). Threads may ask for different voxels at once.
  // Throws what place_voxel_voxlines throws for a damaged file.
  std::optional<std::span<BoxedVoxline>> voxel(std::size_t voxel, const VoxelVoxlines& index);
  // The centre a boxed voxel's distances (near_lo, near_hi) were measured from.
  VoxelReference& reference(std::size_t voxel) { return references_[voxel]; }
  // The sphere the distances follow: region `region` of the selection (-1: none). Another region than the last
  // selection's forgets every voxel's distances.
  void track_region(int region);
  // At the start of each selection: it boxes voxels until they hold kBoxedPerSelection voxlines, and the first
  // selection none (voxel() gives nullopt past that). Boxing a voxel costs more than reading it once without boxes; it
  // pays from the next selection on. So the first selection, which the window waits for with nothing boxed, takes the
  // cheaper way, and each one after it boxes a part, at a bounded cost.
  void selection_started();
  static constexpr std::int64_t kBoxedPerSelection = 1 << 18;
  // After each selection: past half the budget, the voxels it did not use are let go.
  void selection_done();
  std::uint64_t bytes() const { return bytes_; }

 private:
  const VxlFile& file_;
  std::uint64_t budget_;
  std::vector<std::vector<BoxedVoxline>> lists_;  // per voxel; empty until boxed
  std::unique_ptr<std::atomic<bool>[]> boxed_, used_;
  std::vector<VoxelReference> references_;
  int tracked_region_ = -1;
  std::atomic<std::uint64_t> bytes_ = 0;
  std::atomic<std::int64_t> boxing_left_ = 0;  // voxlines the selection under way may still box
  bool selected_before_ = false;
};

}  // namespace vxl
