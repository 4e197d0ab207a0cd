// Every streamline's voxlines as the counting pass found them (voxelize_streamline), in source order, so that
// the placing passes cut each streamline's points by them instead of voxelising it again: per voxline its
// voxel (the source's local id) and its source points, 8 bytes, in blocks that never move (no copy as the
// list grows). A streamline with points added at voxel faces is one entry, kVoxelisedAgain: the placing pass
// voxelises it again (the added points are not kept). Where each part of a batch starts is kept too: the
// placing pass reads the same batches, cut the same way (cut_batch).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <utility>
#include <vector>

namespace vxl::streaming {

struct VoxelRun {
  std::uint32_t voxel;   // local id, or VoxelRuns::kVoxelisedAgain
  std::uint32_t points;  // source points (at least one); 0 in a kVoxelisedAgain entry
};

class VoxelRuns {
 public:
  static constexpr std::uint32_t kVoxelisedAgain = 0xFFFFFFFFu;

  // Notes that the part of a batch that starts at streamline `streamline` starts at the list's end.
  void start_part(std::uint64_t streamline) { part_starts_.emplace_back(streamline, size_); }
  void append(std::span<const VoxelRun> runs);
  // Where the part starting at streamline `streamline` starts; nullopt when no part started there.
  std::optional<std::uint64_t> part_start(std::uint64_t streamline) const;

  std::uint64_t size() const { return size_; }
  const VoxelRun& operator[](std::uint64_t i) const { return blocks_[i >> kBlockShift][i & kBlockMask]; }
  // The memory it holds.
  std::uint64_t bytes() const {
    return blocks_.size() * kBlockRuns * sizeof(VoxelRun) +
           part_starts_.capacity() * sizeof(std::pair<std::uint64_t, std::uint64_t>);
  }
  void clear() { *this = VoxelRuns(); }

 private:
  static constexpr unsigned kBlockShift = 20;  // 1M runs (8 MB) a block
  static constexpr std::uint64_t kBlockRuns = 1ull << kBlockShift, kBlockMask = kBlockRuns - 1;
  std::vector<std::unique_ptr<VoxelRun[]>> blocks_;
  std::uint64_t size_ = 0;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> part_starts_;  // (streamline, run), in order
};

}  // namespace vxl::streaming
