#include "converter/pipeline/voxel_runs.h"

#include <algorithm>

namespace vxl::streaming {

void VoxelRuns::append(std::span<const VoxelRun> runs) {
  for (std::size_t done = 0; done < runs.size();) {
    if ((size_ >> kBlockShift) == blocks_.size())
      blocks_.push_back(std::make_unique_for_overwrite<VoxelRun[]>(kBlockRuns));
    const std::uint64_t in_block = size_ & kBlockMask;
    const std::uint64_t n = std::min<std::uint64_t>(runs.size() - done, kBlockRuns - in_block);
    std::copy_n(runs.data() + done, n, blocks_.back().get() + in_block);
    done += n;
    size_ += n;
  }
}

std::optional<std::uint64_t> VoxelRuns::part_start(std::uint64_t streamline) const {
  const auto it =
      std::lower_bound(part_starts_.begin(), part_starts_.end(), streamline,
                       [](const std::pair<std::uint64_t, std::uint64_t>& p, std::uint64_t s) { return p.first < s; });
  if (it == part_starts_.end() || it->first != streamline) return std::nullopt;
  return it->second;
}

}  // namespace vxl::streaming
