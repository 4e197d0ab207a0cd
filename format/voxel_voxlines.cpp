#include "format/voxel_voxlines.h"

#include <algorithm>
#include <limits>

#include "format/base/error.h"
#include "format/base/parallel.h"
#include "format/vxl_levels.h"

namespace vxl {
namespace {

// STRM as spec §5.7 has it: from 0, non-decreasing, ending at the voxline count.

}  // namespace

std::optional<VoxelVoxlines> VoxelVoxlines::build(const VxlFile& file, unsigned threads) {
  const auto strm = file.streamline_first_voxline();
  const auto voxlines = file.voxlines();
  const std::size_t voxel_count = file.voxels().size();
  const std::uint64_t n = file.meta().streamline_count;
  if (n > std::numeric_limits<std::uint32_t>::max()) return std::nullopt;
  file.check_streamline_table();
  const std::uint32_t levels = file.level_count();

  // A counting sort in contiguous runs of streamlines, one count row per run, so that runs count and
  // scatter side by side and each voxel's list still comes out in streamline order. Fewer runs when the
  // rows would outweigh the table (many voxels, few voxlines).
  const std::uint64_t runs =
      std::clamp<std::uint64_t>(voxlines.size() / (4 * voxel_count + 1), 1, std::max<std::uint64_t>(n, 1));
  const std::uint64_t chunks = std::min<std::uint64_t>(runs, resolve_threads(threads));
  const std::uint64_t per_chunk = (n + chunks - 1) / chunks;
  auto streamlines_of = [&](std::uint64_t c) {
    return std::pair(std::min(c * per_chunk, n), std::min((c + 1) * per_chunk, n));
  };
  std::vector<std::uint64_t> at(chunks * voxel_count, 0);
  bool too_long = false;
  parallel_for_first_error_in_order(chunks, threads, [&](std::uint64_t c, unsigned) {
    std::uint64_t* row = &at[c * voxel_count];
    const auto [begin, end] = streamlines_of(c);
    for (std::uint64_t j = strm[begin]; j < strm[end]; ++j) {
      const VoxlineEntry& e = voxlines[j];
      file.check_voxline(j);
      const std::uint32_t own = e.count_flags & kVoxlineCountMask;
      if (own > IndexedVoxline::kCountMask) too_long = true;
      ++row[e.voxel];
    }
  });
  if (too_long) return std::nullopt;

  VoxelVoxlines index;
  index.first_.assign(voxel_count + 1, 0);
  std::uint64_t total = 0;
  for (std::size_t v = 0; v < voxel_count; ++v) {
    index.first_[v] = total;
    for (std::uint64_t c = 0; c < chunks; ++c) {
      const std::uint64_t count = at[c * voxel_count + v];
      at[c * voxel_count + v] = total;  // becomes where run c writes voxel v's next voxline
      total += count;
    }
  }
  index.first_[voxel_count] = total;
  index.entries_.resize(total);
  parallel_for(chunks, threads, [&](std::uint64_t c, unsigned) {
    std::uint64_t* row = &at[c * voxel_count];
    const auto [begin, end] = streamlines_of(c);
    for (std::uint64_t s = begin; s < end; ++s) {
      const std::uint32_t depth = streamline_depth(s, levels) << 29;
      for (std::uint64_t j = strm[s]; j < strm[s + 1]; ++j) {
        const VoxlineEntry& e = voxlines[j];
        std::uint32_t bits = (e.count_flags & kVoxlineCountMask) | depth;
        if (e.count_flags & kVoxlineSyntheticFirst) bits |= IndexedVoxline::kSyntheticFirst;
        if (j == strm[s]) bits |= IndexedVoxline::kFirstOfStreamline;
        if (j + 1 == strm[s + 1]) bits |= IndexedVoxline::kLastOfStreamline;
        index.entries_[row[e.voxel]++] = {std::uint32_t(s), bits};
      }
    }
  });
  return index;
}

VoxelVoxlinesCache::VoxelVoxlinesCache(std::vector<const VxlFile*> files)
    : files_(std::move(files)), once_(new std::once_flag[files_.size()]), indexes_(files_.size()) {}

const VoxelVoxlines* VoxelVoxlinesCache::of(std::size_t file) {
  std::call_once(once_[file], [&] { indexes_[file] = VoxelVoxlines::build(*files_[file]); });
  return indexes_[file] ? &*indexes_[file] : nullptr;
}

}  // namespace vxl
