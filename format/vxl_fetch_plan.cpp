#include "format/vxl_fetch_plan.h"

#include <algorithm>
#include <cstring>
#include <iterator>

#include "format/base/memory_available.h"
#include "format/vxl_levels.h"
#include "format/vxl_value_sets.h"

namespace vxl {

std::vector<ByteRange> merge_ranges(std::vector<ByteRange> ranges, std::uint64_t gap) {
  std::erase_if(ranges, [](const ByteRange& r) { return r.end <= r.begin; });
  std::sort(ranges.begin(), ranges.end(), [](const ByteRange& a, const ByteRange& b) { return a.begin < b.begin; });
  std::vector<ByteRange> merged;
  for (const ByteRange& r : ranges) {
    if (!merged.empty() && r.begin <= merged.back().end + gap)
      merged.back().end = std::max(merged.back().end, r.end);
    else
      merged.push_back(r);
  }
  return merged;
}

std::vector<ByteRange> ranges_to_open(const std::string& path, std::span<const std::uint8_t> first,
                                      std::uint64_t file_size) {
  const std::vector<SectionEntry> sections = VxlFile::read_section_table(path, first, file_size);
  auto id_of = [](const SectionEntry& e) {
    std::uint32_t id;
    std::memcpy(&id, e.id, 4);
    return id;
  };
  std::uint64_t voxel_count = 0;
  for (const SectionEntry& e : sections)
    if (id_of(e) == section_id("VOXT")) voxel_count = e.size / sizeof(VoxelEntry);
  std::vector<ByteRange> ranges{{0, sizeof(FileHeader) + sections.size() * sizeof(SectionEntry)}};
  for (const SectionEntry& e : sections) {
    const std::uint32_t id = id_of(e);
    std::uint64_t bytes = e.size;  // what open() reads of it
    if (id == section_id("VERT") || id == section_id("ORDB") || id == section_id("ORDR") || id == section_id("VXLN") ||
        id == section_id("STRM") || id == section_id("SLEN"))
      bytes = 0;
    else if (id == section_id("VXIX"))
      bytes = std::min(e.size, 8 * (voxel_count + 1));
    else if (id == section_id("VVAL") || id == section_id("SVAL"))
      bytes = std::min(e.size, value_sets_data_offset(kMaxValueSets));
    ranges.push_back({e.offset, e.offset + bytes});
  }
  return merge_ranges(std::move(ranges), 0);
}

std::vector<ByteRange> ranges_of_level(const VxlFile& file, std::uint32_t level, std::uint64_t gap) {
  return ranges_of_voxels(file, level, 0, static_cast<std::uint32_t>(file.voxels().size()), gap);
}

void read_ahead_level(const VxlFile& file, std::uint32_t level) {
  // Gaps under 64 KiB are read too: one request instead of two costs less than the bytes between them.
  const std::uint64_t budget = available_memory().value_or(std::uint64_t(1) << 30) / 4;
  for (const ByteRange& r : ranges_prefix(ranges_of_level(file, level, 64 << 10), budget))
    file.will_need(r.begin, r.end - r.begin);
}

std::vector<ByteRange> ranges_prefix(std::span<const ByteRange> ranges, std::uint64_t budget) {
  std::vector<ByteRange> prefix;
  for (const ByteRange& r : ranges) {
    if (budget == 0) break;
    const std::uint64_t take = std::min(budget, r.end - r.begin);
    prefix.push_back({r.begin, r.begin + take});
    budget -= take;
  }
  return prefix;
}

std::vector<ByteRange> ranges_of_voxels(const VxlFile& file, std::uint32_t level, std::uint32_t voxel_first,
                                        std::uint32_t voxel_count, std::uint64_t gap) {
  const std::uint64_t vert = file.find_section(section_id("VERT"))->offset;
  const std::uint64_t orders = file.orders_offset();
  const std::uint64_t vertex_bytes = file.position_encoding() == PositionEncoding::Packed ? 4 : 12;
  const std::uint32_t k = file.meta().stored_order_count;
  std::vector<ByteRange> ranges;
  const std::size_t end = std::min<std::size_t>(file.voxels().size(), std::size_t(voxel_first) + voxel_count);
  ranges.reserve(2 * (end - std::min<std::size_t>(voxel_first, end)));
  for (std::size_t i = voxel_first; i < end; ++i) {
    const VoxelEntry& v = file.voxels()[i];
    const LevelEntry at_level = file.level(i, level);
    const std::uint64_t first = vert + v.vertex_first * vertex_bytes;
    ranges.push_back({first, first + at_level.vertex_count * vertex_bytes});
    const std::uint64_t offset = orders + level_orders_offset(v, file.levels_of(i), level, k, file.order_packing());
    ranges.push_back({offset, offset + level_orders_size(at_level, k, file.order_packing())});
  }
  return merge_ranges(std::move(ranges), gap);
}

std::vector<ByteRange> ranges_missing(std::span<const ByteRange> held, std::uint64_t size) {
  std::vector<ByteRange> missing;
  std::uint64_t at = 0;
  for (const ByteRange& r : held) {
    if (r.begin >= size) break;
    if (r.begin > at) missing.push_back({at, r.begin});
    at = std::max(at, r.end);
  }
  if (at < size) missing.push_back({at, size});
  return missing;
}

bool ranges_held(std::span<const ByteRange> wanted, std::span<const ByteRange> held) {
  for (const ByteRange& r : wanted) {
    if (r.end <= r.begin) continue;
    // The last held range that begins at or before r: r lies in it, or some of r is not held.
    const auto after = std::upper_bound(held.begin(), held.end(), r.begin,
                                        [](std::uint64_t at, const ByteRange& h) { return at < h.begin; });
    if (after == held.begin() || std::prev(after)->end < r.end) return false;
  }
  return true;
}

std::vector<ByteRange> ranges_intersection(std::span<const ByteRange> a, std::span<const ByteRange> b) {
  std::vector<ByteRange> both;
  for (std::size_t i = 0, j = 0; i < a.size() && j < b.size();) {
    const std::uint64_t begin = std::max(a[i].begin, b[j].begin), end = std::min(a[i].end, b[j].end);
    if (begin < end) both.push_back({begin, end});
    if (a[i].end < b[j].end)
      ++i;
    else
      ++j;
  }
  return both;
}

}  // namespace vxl
