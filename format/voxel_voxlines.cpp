#include "format/voxel_voxlines.h"

#include <algorithm>
#include <limits>

#include "format/base/error.h"
#include "format/base/parallel.h"
#include "format/vxl_levels.h"

namespace vxl {
namespace {

// A counting sort of VXLN by voxel in contiguous runs of streamlines, one count row per run, so that runs
// count and scatter side by side and each voxel's list still comes out in streamline order. Fewer runs when
// the rows would outweigh the table (many voxels, few voxlines). check(j) sees voxline j before it is
// counted; false when a voxline has more own points than an entry counts.
template <typename CheckVoxline>
bool fill_lists(std::span<const std::uint64_t> strm, std::span<const VoxlineEntry> voxlines, std::uint32_t levels,
                std::span<std::uint64_t> first, std::span<IndexedVoxline> entries, unsigned threads,
                CheckVoxline&& check) {
  const std::size_t voxel_count = first.size() - 1;
  const std::uint64_t n = strm.size() - 1;
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
      check(j);
      if ((e.count_flags & kVoxlineCountMask) > IndexedVoxline::kCountMask) too_long = true;
      ++row[e.voxel];
    }
  });
  if (too_long) return false;

  std::uint64_t total = 0;
  for (std::size_t v = 0; v < voxel_count; ++v) {
    first[v] = total;
    for (std::uint64_t c = 0; c < chunks; ++c) {
      const std::uint64_t count = at[c * voxel_count + v];
      at[c * voxel_count + v] = total;  // becomes where run c writes voxel v's next voxline
      total += count;
    }
  }
  first[voxel_count] = total;
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
        entries[row[e.voxel]++] = {std::uint32_t(s), bits};
      }
    }
  });
  return true;
}

}  // namespace

std::uint64_t voxel_index_bytes(const MetaSection& meta) {
  if (meta.streamline_count > std::numeric_limits<std::uint32_t>::max()) return 0;
  return 8 * (std::uint64_t(meta.voxel_count) + 1) + 8 * meta.voxline_count;
}

void fill_voxel_index(std::span<const std::uint64_t> strm, std::span<const VoxlineEntry> voxlines,
                      std::uint32_t level_count, std::span<std::uint64_t> first, std::span<IndexedVoxline> entries,
                      unsigned threads, const std::string& path) {
  if (first.empty() || strm.empty() || entries.size() != voxlines.size())
    throw std::logic_error("fill_voxel_index: payload sized for other counts");
  const std::size_t voxel_count = first.size() - 1;
  const bool fits = fill_lists(strm, voxlines, std::max<std::uint32_t>(1, level_count), first, entries, threads,
                               [&](std::uint64_t j) {
                                 if (voxlines[j].voxel >= voxel_count)
                                   throw std::logic_error("fill_voxel_index: voxline in no voxel");
                               });
  if (!fits)
    throw Error(ErrorKind::Unsupported, path, std::nullopt,
                "a voxline of 2^26 points or more in one voxel, more than the voxel index counts; use a smaller "
                "--voxel-size");
}

void fill_voxel_index_payload(std::span<std::uint8_t> payload, std::span<const std::uint64_t> strm,
                              std::span<const VoxlineEntry> voxlines, std::uint32_t level_count, unsigned threads,
                              const std::string& path) {
  const std::uint64_t words = payload.size() / 8;
  if (payload.size() % 8 != 0 || words < voxlines.size() + 1)
    throw std::logic_error("fill_voxel_index_payload: payload sized for other counts");
  auto* first = reinterpret_cast<std::uint64_t*>(payload.data());  // payloads are 64-byte aligned
  const std::uint64_t first_count = words - voxlines.size();
  fill_voxel_index(strm, voxlines, level_count, {first, first_count},
                   {reinterpret_cast<IndexedVoxline*>(first + first_count), voxlines.size()}, threads, path);
}

std::optional<VoxelVoxlines> VoxelVoxlines::build(const VxlFile& file, unsigned threads) {
  if (file.meta().streamline_count > std::numeric_limits<std::uint32_t>::max()) return std::nullopt;
  file.check_streamline_table();
  VoxelVoxlines index;
  index.owned_first_.assign(file.voxels().size() + 1, 0);
  index.owned_entries_.resize(file.voxlines().size());
  if (!fill_lists(file.streamline_first_voxline(), file.voxlines(), file.level_count(), index.owned_first_,
                  index.owned_entries_, threads, [&](std::uint64_t j) { file.check_voxline(j); }))
    return std::nullopt;
  index.first_ = index.owned_first_;
  index.entries_ = index.owned_entries_;
  return index;
}

std::optional<VoxelVoxlines> VoxelVoxlines::of_file(const VxlFile& file, unsigned threads) {
  if (file.voxel_index_first().empty()) return build(file, threads);
  VoxelVoxlines index;
  index.first_ = file.voxel_index_first();
  index.entries_ = file.voxel_index_entries();
  return index;
}

VoxelVoxlinesCache::VoxelVoxlinesCache(std::vector<const VxlFile*> files)
    : files_(std::move(files)), once_(new std::once_flag[files_.size()]), indexes_(files_.size()) {}

const VoxelVoxlines* VoxelVoxlinesCache::of(std::size_t file) {
  std::call_once(once_[file], [&] { indexes_[file] = VoxelVoxlines::of_file(*files_[file]); });
  return indexes_[file] ? &*indexes_[file] : nullptr;
}

}  // namespace vxl
