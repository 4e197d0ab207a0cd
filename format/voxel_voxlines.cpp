#include "format/voxel_voxlines.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>

#include "format/base/error.h"
#include "format/level_voxlines.h"
#include "format/vxl_levels.h"
#include "format/vxl_positions.h"

namespace vxl {
namespace {

// STRM read in order, a part at a time: at(s) for s that never decreases.
class StreamlineTableReader {
 public:
  StreamlineTableReader(const VoxelIndexIo& io, std::uint64_t entries) : io_(io), entries_(entries) {}
  std::uint64_t at(std::uint64_t s) {
    if (s < first_ || s >= first_ + part_.size()) {
      first_ = s;
      part_.resize(std::min(kVoxelIndexPartEntries, entries_ - s));
      io_.read_streamline_table(first_, part_);
    }
    return part_[s - first_];
  }

 private:
  const VoxelIndexIo& io_;
  std::uint64_t entries_, first_ = 0;
  std::vector<std::uint64_t> part_;
};

// Calls visit(j, e) for every voxline in order, reading VXLN a part at a time.
template <typename Visit>
void each_voxline(const VoxelIndexIo& io, std::uint64_t voxline_count, std::vector<VoxlineEntry>& part, Visit&& visit) {
  for (std::uint64_t first = 0; first < voxline_count; first += part.size()) {
    part.resize(std::min(kVoxelIndexPartEntries, voxline_count - first));
    io.read_voxlines(first, part);
    for (std::size_t k = 0; k < part.size(); ++k) visit(first + k, part[k]);
  }
}

}  // namespace

std::uint64_t voxel_index_bytes(const MetaSection& meta) {
  if (meta.streamline_count > IndexedVoxline::kStreamlineMask + 1ull) return 0;
  return 8 * (std::uint64_t(meta.voxel_count) + 1) + sizeof(IndexedVoxline) * meta.voxline_count;
}

void fill_voxel_index(std::uint64_t voxel_count, std::uint64_t voxline_count, std::uint64_t streamline_count,
                      const VoxelIndexIo& io, std::uint64_t buffer_bytes) {
  if (streamline_count > IndexedVoxline::kStreamlineMask + 1ull)
    throw std::logic_error("fill_voxel_index: more streamlines than an entry numbers");
  // Pass 1: each voxel's list size, then where each list starts (the payload's first part).
  std::vector<std::uint64_t> first(voxel_count + 1, 0);
  std::vector<VoxlineEntry> part;
  each_voxline(io, voxline_count, part, [&](std::uint64_t j, const VoxlineEntry& e) {
    if (io.check) io.check(j, e);
    if (e.voxel >= voxel_count) throw std::logic_error("fill_voxel_index: a voxline in no voxel");
    ++first[e.voxel + 1];
  });
  for (std::uint64_t v = 0; v < voxel_count; ++v) first[v + 1] += first[v];
  io.write({reinterpret_cast<const std::uint8_t*>(first.data()), first.size() * 8});

  // Then the lists, a range of voxels per pass, each written in place in a buffer by a counting sort.
  const std::uint64_t usable =
      io.buffer.empty() ? buffer_bytes : std::min<std::uint64_t>(buffer_bytes, io.buffer.size_bytes());
  const std::uint64_t buffer_entries =
      io.in_place.empty() ? std::max<std::uint64_t>(1, usable / sizeof(IndexedVoxline)) : voxline_count;
  std::vector<IndexedVoxline> buffer;
  std::vector<std::uint64_t> cursor;
  for (std::uint64_t begin = 0; begin < voxel_count;) {
    std::uint64_t end = begin + 1;
    while (end < voxel_count && first[end + 1] - first[begin] <= buffer_entries) ++end;
    std::span<IndexedVoxline> lists = io.in_place;
    if (lists.empty() && first[end] - first[begin] <= io.buffer.size()) {
      lists = io.buffer.first(first[end] - first[begin]);
    } else if (lists.empty()) {
      buffer.resize(first[end] - first[begin]);
      lists = buffer;
    }
    cursor.assign(first.begin() + static_cast<std::ptrdiff_t>(begin), first.begin() + static_cast<std::ptrdiff_t>(end));
    StreamlineTableReader strm(io, streamline_count + 1);
    std::uint64_t s = 0;
    each_voxline(io, voxline_count, part, [&](std::uint64_t j, const VoxlineEntry& e) {
      if (e.voxel < begin || e.voxel >= end) return;
      while (strm.at(s + 1) <= j) ++s;  // the streamline voxline j belongs to (STRM checked by the caller)
      lists[cursor[e.voxel - begin]++ - first[begin]] = indexed_voxline(s, e, j == strm.at(s), j + 1 == strm.at(s + 1));
    });
    if (io.in_place.empty())
      io.write({reinterpret_cast<const std::uint8_t*>(lists.data()), lists.size() * sizeof(IndexedVoxline)});
    begin = end;
  }
}

VoxelIndexLists::VoxelIndexLists(std::span<const std::uint64_t> voxlines) : first_(voxlines.size() + 1, 0) {
  for (std::size_t v = 0; v < voxlines.size(); ++v) first_[v + 1] = first_[v] + voxlines[v];
  next_.assign(first_.begin(), first_.end() - 1);
  entries_.reset(new IndexedVoxline[first_.back()]);
}

bool VoxelIndexLists::add_streamline(std::uint64_t s, std::span<const VoxlineEntry> voxlines) {
  for (std::size_t j = 0; j < voxlines.size(); ++j) {
    const VoxlineEntry& e = voxlines[j];
    if (e.voxel >= next_.size() || next_[e.voxel] == first_[e.voxel + 1]) return false;
    entries_[next_[e.voxel]++] = indexed_voxline(s, e, j == 0, j + 1 == voxlines.size());
  }
  return true;
}

bool VoxelIndexLists::complete() const {
  for (std::size_t v = 0; v < next_.size(); ++v)
    if (next_[v] != first_[v + 1]) return false;
  return true;
}

namespace {

// Reads from tables in memory (a writer's own, or a mapped file's).
VoxelIndexIo tables_in_memory(std::span<const std::uint64_t> strm, std::span<const VoxlineEntry> voxlines) {
  VoxelIndexIo io;
  io.read_voxlines = [voxlines](std::uint64_t first, std::span<VoxlineEntry> out) {
    std::copy_n(voxlines.begin() + static_cast<std::ptrdiff_t>(first), out.size(), out.begin());
  };
  io.read_streamline_table = [strm](std::uint64_t first, std::span<std::uint64_t> out) {
    std::copy_n(strm.begin() + static_cast<std::ptrdiff_t>(first), out.size(), out.begin());
  };
  return io;
}

}  // namespace

void fill_voxel_index_payload(std::span<std::uint8_t> payload, std::span<const std::uint64_t> strm,
                              std::span<const VoxlineEntry> voxlines) {
  const std::uint64_t lists = sizeof(IndexedVoxline) * voxlines.size();
  if (strm.empty() || payload.size() < lists + 8 || (payload.size() - lists) % 8 != 0)
    throw std::logic_error("fill_voxel_index_payload: payload sized for other counts");
  const std::uint64_t starts = payload.size() - lists;
  VoxelIndexIo io = tables_in_memory(strm, voxlines);
  io.write = [&](std::span<const std::uint8_t> bytes) { std::copy(bytes.begin(), bytes.end(), payload.begin()); };
  io.in_place = {reinterpret_cast<IndexedVoxline*>(payload.data() + starts), voxlines.size()};  // 64-byte aligned
  fill_voxel_index(starts / 8 - 1, voxlines.size(), strm.size() - 1, io, lists);
}

std::optional<VoxelVoxlines> VoxelVoxlines::build(const VxlFile& file) {
  if (file.meta().streamline_count > IndexedVoxline::kStreamlineMask + 1ull) return std::nullopt;
  file.check_streamline_table();
  VoxelVoxlines index;
  index.owned_first_.resize(file.voxels().size() + 1);
  index.owned_entries_.resize(file.voxlines().size());
  VoxelIndexIo io = tables_in_memory(file.streamline_first_voxline(), file.voxlines());
  io.write = [&](std::span<const std::uint8_t> bytes) {
    std::memcpy(index.owned_first_.data(), bytes.data(), bytes.size());
  };
  io.check = [&](std::uint64_t j, const VoxlineEntry&) { file.check_voxline(j); };
  io.in_place = index.owned_entries_;
  fill_voxel_index(file.voxels().size(), file.voxlines().size(), file.meta().streamline_count, io, 0);
  index.first_ = index.owned_first_;
  index.entries_ = index.owned_entries_;
  return index;
}

std::optional<VoxelVoxlines> VoxelVoxlines::of_file(const VxlFile& file) {
  if (file.voxel_index_first().empty()) return build(file);
  VoxelVoxlines index;
  index.first_ = file.voxel_index_first();
  index.entries_ = file.voxel_index_entries();
  return index;
}

void place_voxel_voxlines(const VxlFile& file, const VoxelVoxlines& index, std::size_t voxel,
                          std::vector<std::uint8_t>& ends, std::vector<PlacedVoxline>& out, std::uint32_t level) {
  out.clear();
  const VoxelEntry& v = file.voxels()[voxel];
  const std::uint64_t voxt_at = file.find_section(section_id("VOXT"))->offset + sizeof(VoxelEntry) * voxel;
  const std::uint32_t levels = file.level_count();
  const auto row = file.levels_of(voxel);
  level = std::min(level, levels > 0 ? levels - 1 : 0u);
  std::array<std::uint64_t, kMaxLevels> cursor{}, end{};
  for (std::uint32_t d = 0; d < levels; ++d)
    cursor[d] = depth_first_vertex(row, d), end[d] = depth_end_vertex(v, row, d);
  // Where each voxline ends in the level's prefix (spec §5.4): a packed word's end bit, read where the walk below
  // goes; in a float32 block, where the level's order 0 starts no segment (an entry out of range marks nothing:
  // the walk stays in the block).
  const bool packed = file.position_encoding() == PositionEncoding::Packed;
  const std::uint32_t* words = packed ? file.packed_vertices().data() + v.vertex_first : nullptr;
  if (!packed) {
    const std::uint32_t prefix = voxel_level(v, row, level).vertex_count;
    ends.assign(prefix, 1);
    const OrderView starts = file.order(voxel, 0, level);
    for (std::uint32_t k = 0; k < starts.count; ++k)
      if (const std::uint32_t e = starts[k]; e < prefix) ends[e] = 0;
  }
  const std::uint64_t n = file.meta().streamline_count;
  for (const IndexedVoxline& e : index.of_voxel(voxel)) {
    PlacedVoxline p;
    p.streamline = e.streamline();
    if (p.streamline >= n)  // from the file's VXIX, unchecked until now
      fail_input(file.path(), voxt_at,
                 "voxel " + std::to_string(voxel) + "'s list names a streamline past the streamline count");
    p.depth = streamline_depth(p.streamline, levels);
    if (p.depth < level) continue;  // outside the level's prefix
    p.synthetic_first = (e.word & IndexedVoxline::kSyntheticFirst) != 0;
    p.first_of_streamline = (e.word & IndexedVoxline::kFirstOfStreamline) != 0;
    p.last_of_streamline = (e.word & IndexedVoxline::kLastOfStreamline) != 0;
    const std::uint64_t stop_limit = end[p.depth];
    std::uint64_t stop = cursor[p.depth];
    if (packed)
      while (stop < stop_limit && (words[stop] & kPackedVoxlineEnd) == 0) ++stop;
    else
      while (stop < stop_limit && !ends[stop]) ++stop;
    const std::uint64_t vertices = stop - cursor[p.depth] + 1;
    if (stop >= stop_limit || vertices <= (p.last_of_streamline ? 0u : 1u))
      fail_input(file.path(), voxt_at, "the voxel's voxlines run past its vertex block (or a level's part of it)");
    p.own = static_cast<std::uint32_t>(vertices - (p.last_of_streamline ? 0 : 1));
    p.first_vertex = v.vertex_first + cursor[p.depth];
    cursor[p.depth] = stop + 1;
    out.push_back(p);
  }
}

struct VoxelVoxlinesCache::Levels {
  std::array<std::once_flag, kMaxLevels> once;
  std::array<std::optional<LevelVoxlines>, kMaxLevels> placed;
};

VoxelVoxlinesCache::VoxelVoxlinesCache(std::vector<const VxlFile*> files)
    : files_(std::move(files)),
      once_(new std::once_flag[files_.size()]),
      indexes_(files_.size()),
      levels_(new Levels[files_.size()]) {}

VoxelVoxlinesCache::~VoxelVoxlinesCache() = default;

const LevelVoxlines& VoxelVoxlinesCache::level(std::size_t file, std::uint32_t level) {
  if (level >= kMaxLevels) throw std::logic_error("VoxelVoxlinesCache::level: no such level");
  Levels& l = levels_[file];
  std::call_once(l.once[level], [&] { l.placed[level].emplace(*files_[file], level); });
  return *l.placed[level];
}

const VoxelVoxlines* VoxelVoxlinesCache::of(std::size_t file) {
  std::call_once(once_[file], [&] { indexes_[file] = VoxelVoxlines::of_file(*files_[file]); });
  return indexes_[file] ? &*indexes_[file] : nullptr;
}

}  // namespace vxl
