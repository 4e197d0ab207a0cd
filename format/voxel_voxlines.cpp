#include "format/voxel_voxlines.h"

#include <algorithm>
#include <array>
#include <limits>

#include "format/base/error.h"
#include "format/base/parallel.h"
#include "format/vxl_levels.h"
#include "format/vxl_positions.h"

namespace vxl {
namespace {

// A counting sort of VXLN by voxel in contiguous runs of streamlines, one count row per run, so that runs
// count and scatter side by side and each voxel's list still comes out in streamline order. Fewer runs when
// the rows would outweigh the table (many voxels, few voxlines). check(j) sees voxline j before it is counted.
template <typename CheckVoxline>
void fill_lists(std::span<const std::uint64_t> strm, std::span<const VoxlineEntry> voxlines,
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
  parallel_for_first_error_in_order(chunks, threads, [&](std::uint64_t c, unsigned) {
    std::uint64_t* row = &at[c * voxel_count];
    const auto [begin, end] = streamlines_of(c);
    for (std::uint64_t j = strm[begin]; j < strm[end]; ++j) {
      check(j);
      ++row[voxlines[j].voxel];
    }
  });

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
    for (std::uint64_t s = begin; s < end; ++s)
      for (std::uint64_t j = strm[s]; j < strm[s + 1]; ++j) {
        const VoxlineEntry& e = voxlines[j];
        std::uint32_t word = static_cast<std::uint32_t>(s);
        if (e.count_flags & kVoxlineSyntheticFirst) word |= IndexedVoxline::kSyntheticFirst;
        if (j == strm[s]) word |= IndexedVoxline::kFirstOfStreamline;
        if (j + 1 == strm[s + 1]) word |= IndexedVoxline::kLastOfStreamline;
        entries[row[e.voxel]++] = {word};
      }
  });
}

}  // namespace

std::uint64_t voxel_index_bytes(const MetaSection& meta) {
  if (meta.streamline_count > IndexedVoxline::kStreamlineMask + 1ull) return 0;
  return 8 * (std::uint64_t(meta.voxel_count) + 1) + sizeof(IndexedVoxline) * meta.voxline_count;
}

void fill_voxel_index(std::span<const std::uint64_t> strm, std::span<const VoxlineEntry> voxlines,
                      std::span<std::uint64_t> first, std::span<IndexedVoxline> entries, unsigned threads) {
  if (first.empty() || strm.empty() || entries.size() != voxlines.size() ||
      strm.size() - 1 > IndexedVoxline::kStreamlineMask + 1ull)
    throw std::logic_error("fill_voxel_index: payload sized for other counts");
  const std::size_t voxel_count = first.size() - 1;
  fill_lists(strm, voxlines, first, entries, threads, [&](std::uint64_t j) {
    if (voxlines[j].voxel >= voxel_count) throw std::logic_error("fill_voxel_index: voxline in no voxel");
  });
}

void fill_voxel_index_payload(std::span<std::uint8_t> payload, std::span<const std::uint64_t> strm,
                              std::span<const VoxlineEntry> voxlines, unsigned threads) {
  const std::uint64_t lists = sizeof(IndexedVoxline) * voxlines.size();
  if (payload.size() < lists + 8 || (payload.size() - lists) % 8 != 0)
    throw std::logic_error("fill_voxel_index_payload: payload sized for other counts");
  auto* first = reinterpret_cast<std::uint64_t*>(payload.data());  // payloads are 64-byte aligned
  const std::uint64_t first_count = (payload.size() - lists) / 8;
  fill_voxel_index(strm, voxlines, {first, first_count},
                   {reinterpret_cast<IndexedVoxline*>(first + first_count), voxlines.size()}, threads);
}

std::optional<VoxelVoxlines> VoxelVoxlines::build(const VxlFile& file, unsigned threads) {
  if (file.meta().streamline_count > IndexedVoxline::kStreamlineMask + 1ull) return std::nullopt;
  file.check_streamline_table();
  VoxelVoxlines index;
  index.owned_first_.assign(file.voxels().size() + 1, 0);
  index.owned_entries_.resize(file.voxlines().size());
  fill_lists(file.streamline_first_voxline(), file.voxlines(), index.owned_first_, index.owned_entries_, threads,
             [&](std::uint64_t j) { file.check_voxline(j); });
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

void place_voxel_voxlines(const VxlFile& file, const VoxelVoxlines& index, std::size_t voxel,
                          std::vector<std::uint8_t>& ends, std::vector<PlacedVoxline>& out) {
  out.clear();
  const VoxelEntry& v = file.voxels()[voxel];
  const std::uint64_t voxt_at = file.find_section(section_id("VOXT"))->offset + sizeof(VoxelEntry) * voxel;
  // Where each voxline ends in the block (spec §5.4): the packed words say it; float32 blocks by order 0, which
  // starts a segment at every other vertex (an entry out of range marks nothing: the walk below stays in the block).
  ends.assign(v.vertex_count, 1);
  if (file.position_encoding() == PositionEncoding::Packed) {
    const std::uint32_t* words = file.packed_vertices().data() + v.vertex_first;
    for (std::uint32_t i = 0; i < v.vertex_count; ++i) ends[i] = (words[i] & kPackedVoxlineEnd) != 0;
  } else {
    const OrderView starts = file.order(voxel, 0, 0);
    for (std::uint32_t k = 0; k < starts.count; ++k)
      if (const std::uint32_t e = starts[k]; e < v.vertex_count) ends[e] = 0;
  }
  const std::uint32_t levels = file.level_count();
  const auto row = file.levels_of(voxel);
  std::array<std::uint64_t, kMaxLevels> cursor{}, end{};
  for (std::uint32_t d = 0; d < levels; ++d)
    cursor[d] = depth_first_vertex(row, d), end[d] = depth_end_vertex(v, row, d);
  const std::uint64_t n = file.meta().streamline_count;
  for (const IndexedVoxline& e : index.of_voxel(voxel)) {
    PlacedVoxline p;
    p.streamline = e.streamline();
    if (p.streamline >= n)  // from the file's VXIX, unchecked until now
      fail_input(file.path(), voxt_at,
                 "voxel " + std::to_string(voxel) + "'s list names a streamline past the streamline count");
    p.depth = streamline_depth(p.streamline, levels);
    p.synthetic_first = (e.word & IndexedVoxline::kSyntheticFirst) != 0;
    p.first_of_streamline = (e.word & IndexedVoxline::kFirstOfStreamline) != 0;
    p.last_of_streamline = (e.word & IndexedVoxline::kLastOfStreamline) != 0;
    std::uint64_t stop = cursor[p.depth];
    while (stop < end[p.depth] && !ends[stop]) ++stop;
    const std::uint64_t vertices = stop - cursor[p.depth] + 1;
    if (stop >= end[p.depth] || vertices <= (p.last_of_streamline ? 0u : 1u))
      fail_input(file.path(), voxt_at, "the voxel's voxlines run past its vertex block (or a level's part of it)");
    p.own = static_cast<std::uint32_t>(vertices - (p.last_of_streamline ? 0 : 1));
    p.first_vertex = v.vertex_first + cursor[p.depth];
    cursor[p.depth] = stop + 1;
    out.push_back(p);
  }
}

VoxelVoxlinesCache::VoxelVoxlinesCache(std::vector<const VxlFile*> files)
    : files_(std::move(files)), once_(new std::once_flag[files_.size()]), indexes_(files_.size()) {}

const VoxelVoxlines* VoxelVoxlinesCache::of(std::size_t file) {
  std::call_once(once_[file], [&] { indexes_[file] = VoxelVoxlines::of_file(*files_[file]); });
  return indexes_[file] ? &*indexes_[file] : nullptr;
}

}  // namespace vxl
