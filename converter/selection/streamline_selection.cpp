#include "converter/selection/streamline_selection.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <new>
#include <string>

#include <nlohmann/json.hpp>

#include "converter/selection/length_limits.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/base/parallel.h"
#include "format/streamline_length.h"
#include "format/vxl_positions.h"
#include "format/vxl_streamlines.h"

namespace vxl {
namespace {

using Bits = std::uint64_t;

// The regions, numbered: includes first, then ends-in, then excludes (bit r is region r).
struct RegionTable {
  std::vector<const Region*> regions;
  Bits include = 0, ends = 0, exclude = 0;

  explicit RegionTable(const SelectionCriteria& c) {
    auto add = [&](const std::vector<Region>& list, Bits& kind) {
      for (const Region& r : list) {
        kind |= Bits(1) << regions.size();
        regions.push_back(&r);
      }
    };
    if (c.include.size() + c.ends_in.size() + c.exclude.size() > kMaxRegions)
      throw Error(ErrorKind::Usage, "regions", std::nullopt,
                  "at most " + std::to_string(kMaxRegions) + " regions in one selection");
    add(c.include, include);
    add(c.ends_in, ends);
    add(c.exclude, exclude);
  }
};

// Per voxel, the regions that may touch its bounds and those that hold them whole (decoded packed positions
// may stray from the tight bounds by the file's error bound, so the box is widened by it).
struct VoxelRegions {
  std::vector<Bits> touching, holding;
};
VoxelRegions regions_per_voxel(const VxlFile& file, const RegionTable& table, std::uint32_t& touched) {
  const auto voxels = file.voxels();
  const bool packed = file.position_encoding() == PositionEncoding::Packed;
  VoxelRegions out{std::vector<Bits>(voxels.size(), 0), std::vector<Bits>(voxels.size(), 0)};
  touched = 0;
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    const VoxelEntry& v = voxels[i];
    float lo[3], hi[3];
    const float widen = packed ? static_cast<float>(packed_error_bound(v)) : 0.0f;
    for (int c = 0; c < 3; ++c) lo[c] = v.tight_min[c] - widen, hi[c] = v.tight_max[c] + widen;
    for (std::size_t r = 0; r < table.regions.size(); ++r) {
      if (table.regions[r]->may_touch(lo, hi)) out.touching[i] |= Bits(1) << r;
      if (table.regions[r]->holds_box(lo, hi)) out.holding[i] |= Bits(1) << r;
    }
    touched += out.touching[i] != 0;
  }
  return out;
}

// Whether SLEN's length decides the limits as tckedit's float32 measure of the same points would: it lies farther
// from each limit than the two can differ. tckedit's sum of n - 1 segment lengths, each within 5 roundings, is
// within (n + 5) float32 roundings (2^-24 of the length each) of the exact length, and SLEN within one: twice
// (n + 16) of them is a safe margin.
bool slen_decides(double length, const LengthLimits& limits, std::uint64_t points) {
  const double tolerance = double(points + 16) * 0x1p-23 * length;
  return !(std::fabs(length - limits.min) <= tolerance) && !(std::fabs(length - limits.max) <= tolerance);
}

// Streamline s's source points: its voxlines' own point counts.
std::uint64_t streamline_point_count(const VxlFile& file, std::uint64_t s) {
  file.check_streamline_run(s);
  const std::span<const std::uint64_t> first = file.streamline_first_voxline();
  std::uint64_t points = 0;
  for (const VoxlineEntry& v : file.voxlines().subspan(first[s], first[s + 1] - first[s]))
    points += v.count_flags & kVoxlineCountMask;
  return points;
}

// The regions each streamline's points fell in, one word a streamline. Its zeroed pages come from the system as
// they are first written (calloc), so a small query touches little of it, and a large one costs 8 bytes a
// streamline: a list of (streamline, regions) per hit voxline, to be sorted and merged, would take 16 bytes a
// voxline twice over (400 MB for a box holding the 1M set).
class RegionHits {
 public:
  explicit RegionHits(std::uint64_t streamlines)
      : bits_(static_cast<Bits*>(std::calloc(std::max<std::uint64_t>(streamlines, 1), sizeof(Bits)))) {
    if (!bits_) throw std::bad_alloc();
  }
  // From any thread.
  void add(std::uint64_t streamline, Bits regions) {
    std::atomic_ref<Bits>(bits_.get()[streamline]).fetch_or(regions, std::memory_order_relaxed);
  }
  Bits operator[](std::uint64_t streamline) const { return bits_.get()[streamline]; }

 private:
  struct Free {
    void operator()(Bits* p) const { std::free(p); }
  };
  std::unique_ptr<Bits, Free> bits_;
};

// One voxline, as a region test needs it.
struct VoxlinePlace {
  std::uint32_t voxel = 0, own = 0;
  bool synthetic_first = false, first_of_streamline = false, connected = false;
  std::uint64_t first_vertex = 0;
};

// What the two ways of finding the hits share: the regions, the voxels they may touch, the file's tables.
struct HitSearch {
  const VxlFile& file;
  const RegionTable& table;
  const VoxelRegions& voxel_regions;
  std::uint64_t points_tested = 0;
  std::span<const std::uint64_t> strm = file.streamline_first_voxline();
  std::span<const VoxlineEntry> voxlines = file.voxlines();
  std::span<const VoxelEntry> voxels = file.voxels();
  std::uint32_t levels = file.level_count();
  std::uint64_t vxln_at = file.find_section(section_id("VXLN"))->offset;
  std::vector<float> xyz = {};

  // Tests one voxline in a voxel the regions may touch against those regions still `open` for its
  // streamline; returns the regions holding one of its points.
  Bits test_voxline(const VoxlinePlace& v, Bits open) {
    const Bits touching = voxel_regions.touching[v.voxel] & open;
    const Bits anywhere = touching & (table.include | table.exclude);
    const Bits at_ends = (v.first_of_streamline || !v.connected) ? touching & table.ends : 0;
    if ((anywhere | at_ends) == 0) return 0;
    const std::uint32_t from = v.synthetic_first ? 1 : 0;
    if (from >= v.own) return 0;  // only a synthetic point: nothing to test
    // A region holding the whole voxel holds every point tested here (a voxline's end point is a source
    // point: synthetic points are never first or last of a streamline).
    const Bits held = voxel_regions.holding[v.voxel];
    Bits hit = (anywhere | at_ends) & held;
    const Bits left = (anywhere | at_ends) & ~held;
    if (left == 0) return hit;
    xyz.resize(3 * std::size_t(v.own));
    file.read_vertices(v.voxel, v.first_vertex, v.own, xyz.data());
    points_tested += v.own - from;
    for (std::uint32_t i = from; i < v.own; ++i) {
      const float* p = &xyz[3 * std::size_t(i)];
      Bits test = anywhere & left & ~hit;
      if ((i == 0 && v.first_of_streamline) || (i + 1 == v.own && !v.connected)) test |= at_ends & left & ~hit;
      for (Bits b = test; b != 0; b &= b - 1) {
        const int r = std::countr_zero(b);
        if (table.regions[r]->contains(p)) hit |= Bits(1) << r;
      }
    }
    return hit;
  }

  // Where the voxlines of depth `depth` start and end in a voxel's block (spec §5.4, §5.12).
  std::uint64_t depth_start(std::size_t voxel, std::uint32_t depth) const {
    return voxels[voxel].vertex_first + depth_first_vertex(file.levels_of(voxel), depth);
  }
  std::uint64_t depth_end(std::size_t voxel, std::uint32_t depth) const {
    return voxels[voxel].vertex_first + depth_end_vertex(voxels[voxel], file.levels_of(voxel), depth);
  }
};

// Claims a voxline's vertices at its voxel's `cursor` (for its depth; the part ends at `end`): `own` plus
// the connecting vertex unless it ends its streamline. False when they run past the end.
bool claim_vertices(VoxlinePlace& v, std::uint64_t& cursor, std::uint64_t end) {
  const std::uint64_t need = std::uint64_t(v.own) + (v.connected ? 1 : 0);
  if (cursor > end || need > end - cursor) return false;
  v.first_vertex = cursor;
  cursor += need;
  return true;
}

// Every streamline in order, through the whole voxline table. A voxline's vertices are found by its
// voxel's cursor (spec §5.6), so cursors are kept for the touched voxels alone and a voxline elsewhere
// costs one table entry and one look at its voxel's bits; written out rather than run through
// walk_streamlines' callbacks for that reason (the empty query on the 1M set went from 0.3 s to 0.12 s).
void hits_by_scan(HitSearch& q, RegionHits& hits, std::uint64_t& bytes_read) {
  const std::uint64_t n = q.file.meta().streamline_count;
  std::vector<std::uint64_t> cursor(q.voxels.size() * q.levels, 0), end(cursor.size(), 0);
  for (std::size_t i = 0; i < q.voxels.size(); ++i)
    if (q.voxel_regions.touching[i] != 0)
      for (std::uint32_t d = 0; d < q.levels; ++d)
        cursor[i * q.levels + d] = q.depth_start(i, d), end[i * q.levels + d] = q.depth_end(i, d);
  for (std::uint64_t s = 0; s < n; ++s) {
    const std::uint64_t first = q.strm[s], last = q.strm[s + 1];
    q.file.check_streamline_run(s);
    Bits hit = 0;
    const std::uint32_t depth = streamline_depth(s, q.levels);
    for (std::uint64_t j = first; j < last; ++j) {
      const VoxlineEntry& e = q.voxlines[j];
      q.file.check_voxline(j);
      if (q.voxel_regions.touching[e.voxel] == 0) continue;
      VoxlinePlace v{e.voxel, e.count_flags & kVoxlineCountMask, (e.count_flags & kVoxlineSyntheticFirst) != 0,
                     j == first, j + 1 < last};
      const std::size_t k = std::size_t(e.voxel) * q.levels + depth;
      if (!claim_vertices(v, cursor[k], end[k]))
        fail_input(q.file.path(), q.vxln_at + 8 * j,
                   "voxline runs past its voxel's vertex block (or its level's part of it)");
      hit |= q.test_voxline(v, ~hit);
    }
    if (hit != 0) hits.add(s, hit);
  }
  bytes_read += q.strm.size_bytes() + q.voxlines.size_bytes();
}

// Only the voxels the regions may touch, through their lists (VoxelVoxlines): a voxel's list, placed in its
// block (place_voxel_voxlines), is all a voxline costs. Voxels are independent here, so they are searched side
// by side (the first error in voxel order reported).
void hits_by_index(HitSearch& q, const VoxelVoxlines& index, RegionHits& hits, std::uint64_t& bytes_read) {
  std::vector<std::uint32_t> touched;
  for (std::size_t voxel = 0; voxel < q.voxels.size(); ++voxel)
    if (q.voxel_regions.touching[voxel] != 0) touched.push_back(std::uint32_t(voxel));
  struct Scratch {
    std::vector<std::uint8_t> ends;
    std::vector<PlacedVoxline> placed;
  };
  std::vector<HitSearch> per_thread(resolve_threads(0), q);
  std::vector<Scratch> scratch(per_thread.size());
  // A query touching most voxels reads most blocks: their pages are let go as it goes (walk_streamlines does so too).
  std::atomic<std::uint64_t> read_since_release = 0;
  parallel_for_first_error_in_order(touched.size(), 0, [&](std::uint64_t k, unsigned t) {
    HitSearch& search = per_thread[t];
    const std::uint32_t voxel = touched[k];
    if (read_since_release.fetch_add(4ull * q.voxels[voxel].vertex_count) > (64ull << 20)) {
      read_since_release = 0;
      q.file.release_resident_pages();
    }
    place_voxel_voxlines(q.file, index, voxel, scratch[t].ends, scratch[t].placed);
    for (const PlacedVoxline& p : scratch[t].placed) {
      VoxlinePlace v{voxel, p.own, p.synthetic_first, p.first_of_streamline, !p.last_of_streamline, p.first_vertex};
      if (const Bits hit = search.test_voxline(v, ~Bits(0)); hit != 0) hits.add(p.streamline, hit);
    }
  });
  for (std::size_t k = 0; k < touched.size(); ++k) {
    // The list, and the block's voxline ends: its packed words (float32: order 0), read whole.
    const VoxelEntry& v = q.voxels[touched[k]];
    bytes_read += index.of_voxel(touched[k]).size_bytes() +
                  (q.file.position_encoding() == PositionEncoding::Packed
                       ? 4ull * v.vertex_count
                       : order_array_bytes(v.segment_count, q.file.order(touched[k], 0).bits));
  }
  for (const HitSearch& search : per_thread) q.points_tested += search.points_tested;
}

}  // namespace

SelectionResult select_streamlines(const VxlFile& file, const SelectionCriteria& criteria, const VoxelVoxlines* index,
                                   SelectionPath path) {
  if (criteria.min_length && criteria.max_length && *criteria.min_length > *criteria.max_length)
    throw Error(ErrorKind::Usage, "--min-length", std::nullopt, "the minimum length is above the maximum length");
  const RegionTable table(criteria);
  SelectionResult result;
  const std::uint64_t n = file.meta().streamline_count;
  // The tables whose values decide membership are checksummed before they are trusted (once per file: the
  // window's selections pay once). The vertex blocks, read in part, are checked for structure as they are read.
  auto trust = [&file](const char(&id)[5]) { file.check_section_checksum(section_id(id)); };
  trust("VOXT");
  trust("STRM");
  const VoxelRegions voxel_regions = regions_per_voxel(file, table, result.voxels_touched);
  result.bytes_read = file.voxels().size_bytes();
  HitSearch search{file, table, voxel_regions};
  // The file's own index costs nothing to use; one is built only by callers that keep it (the viewer).
  std::optional<VoxelVoxlines> file_index;
  if (path == SelectionPath::ScanTable) {
    index = nullptr;
  } else if (!index && !file.voxel_index_first().empty()) {
    file_index = VoxelVoxlines::of_file(file);
    index = file_index ? &*file_index : nullptr;
  }
  trust(index && !file.voxel_index_first().empty() ? "VXIX" : "VXLN");
  RegionHits hits(n);
  if (index)
    hits_by_index(search, *index, hits, result.bytes_read);
  else
    hits_by_scan(search, hits, result.bytes_read);
  result.points_tested = search.points_tested;

  const Bits needed = table.include | table.ends;
  std::vector<std::uint8_t> passes(n, needed == 0 ? 1 : 0);
  result.streamlines_per_region.assign(table.regions.size(), 0);
  for (std::uint64_t s = 0; s < n; ++s) {
    const Bits regions = hits[s];
    if (regions == 0) continue;
    passes[s] = (regions & needed) == needed && (regions & table.exclude) == 0;
    for (Bits b = regions; b != 0; b &= b - 1) ++result.streamlines_per_region[std::countr_zero(b)];
  }
  const std::uint64_t vertex_bytes = file.position_encoding() == PositionEncoding::Packed ? 4 : 12;
  result.bytes_read += result.points_tested * vertex_bytes;

  // Length limits, for the streamlines still in (tckedit applies its thresholds even without options: a header
  // can make them cut). SLEN decides a packed file's lengths: its points are not the source's, and SLEN is
  // within (points + 5) float32 roundings of tckedit's length. With float32 positions SLEN decides where it lies
  // farther than that from both limits, and the points of the rest are measured as tckedit measures them, so
  // the answer is tckedit's to the bit. Files without SLEN, and the table-walking path, measure every length.
  const LengthLimits limits = tckedit_length_limits(file, criteria.min_length, criteria.max_length);
  if (!limits.keep_every_length()) {
    constexpr std::uint8_t kMeasure = 2;
    const bool slen = !file.streamline_lengths().empty() && path == SelectionPath::Fastest;
    const bool source_points = file.position_encoding() == PositionEncoding::Float32;
    if (slen) trust("SLEN");
    if (!slen || source_points) trust("VXLN");  // walked, or counted for the streamlines near a limit
    for (std::uint64_t s = 0; s < n; ++s) {
      if (passes[s] == 0) continue;
      if (!slen) {
        passes[s] = kMeasure;
        continue;
      }
      ++result.lengths_read;
      const double length = stored_length(file, s);
      passes[s] = !source_points || slen_decides(length, limits, streamline_point_count(file, s))
                      ? std::uint8_t(limits.keeps(static_cast<float>(length)))
                      : kMeasure;
    }
    result.bytes_read += 4 * result.lengths_read;
    WalkCallbacks lengths;
    lengths.read_points = [&](std::uint64_t s) { return passes[s] == kMeasure; };
    lengths.streamline = [&](std::uint64_t s, std::span<const float> points) {
      ++result.streamlines_measured;
      result.bytes_read += points.size() / 3 * vertex_bytes;
      passes[s] = limits.keeps(float32_polyline_length(points));
    };
    if (std::find(passes.begin(), passes.end(), kMeasure) != passes.end()) walk_streamlines(file, lengths);
  }
  // A streamline without points is never kept, inverted or not: tckedit's reader skips it, so it never writes one.
  const std::span<const std::uint64_t> first_voxline = file.streamline_first_voxline();
  for (std::uint64_t s = 0; s < n; ++s)
    if ((passes[s] != 0) != criteria.invert && first_voxline[s + 1] != first_voxline[s])
      result.streamlines.push_back(s);
  return result;
}

}  // namespace vxl
