#include "converter/selection/streamline_selection.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "converter/selection/length_limits.h"
#include "converter/selection/voxline_boxes.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/base/parallel.h"
#include "format/level_voxlines.h"
#include "format/streamline_length.h"
#include "format/vxl_levels.h"
#include "format/vxl_positions.h"
#include "format/vxl_streamlines.h"

namespace vxl {
namespace {

using Bits = std::uint64_t;

// The regions, numbered: includes first, then ends-in, then excludes (bit r is region r).
struct RegionTable {
  std::vector<const Region*> regions;
  std::vector<std::array<float, 6>> reach;  // per region: Region::reach's lo, then hi
  Bits include = 0, ends = 0, exclude = 0;

  explicit RegionTable(const SelectionCriteria& c) {
    auto add = [&](const std::vector<Region>& list, Bits& kind) {
      for (const Region& r : list) {
        kind |= Bits(1) << regions.size();
        regions.push_back(&r);
        std::array<float, 6>& box = reach.emplace_back();
        r.reach(box.data(), box.data() + 3);
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

// fn(i) for each i, a multiple of 8, where bytes [i, i + 8) of `bytes` are not all zero (the last part padded).
template <typename Fn>
void for_each_nonzero_chunk(const std::uint8_t* bytes, std::uint64_t count, Fn&& fn) {
  const std::uint64_t whole = count / 8 * 8;
  for (std::uint64_t i = 0; i < whole; i += 8) {  // a fixed-size copy: one load, where a variable one is a loop
    std::uint64_t chunk;
    std::memcpy(&chunk, bytes + i, 8);
    if (chunk != 0) fn(i);
  }
  if (whole == count) return;
  std::uint64_t chunk = 0;
  std::memcpy(&chunk, bytes + whole, count - whole);
  if (chunk != 0) fn(whole);
}

// The regions each streamline's points fell in: a byte a streamline for each 8 regions (one byte for most
// selections). Its zeroed pages come from the system as they are first written (calloc), so a small query touches
// little of it, and a large one costs a byte a streamline: a list of (streamline, regions) per hit voxline, to be
// sorted and merged, would take 16 bytes a voxline twice over (400 MB for a box holding the 1M set). Bytes, not a
// word for all 64 regions: the hits land all over the table, and each lands in a cache line of its own.
class RegionHits {
 public:
  RegionHits(std::uint64_t streamlines, std::size_t regions)
      : stride_(std::max<std::size_t>(1, (regions + 7) / 8)),
        bytes_(static_cast<std::uint8_t*>(std::calloc(std::max<std::uint64_t>(streamlines, 1), stride_))) {
    if (!bytes_) throw std::bad_alloc();
  }
  // From any thread.
  void add(std::uint64_t streamline, Bits regions) {
    std::uint8_t* at = bytes_.get() + streamline * stride_;
    for (std::size_t b = 0; b < stride_; ++b)
      if (const auto part = static_cast<std::uint8_t>(regions >> (8 * b)); part != 0) {
        std::atomic_ref<std::uint8_t> byte(at[b]);
        // A streamline crosses a region in several voxlines: the locked OR only where a bit is new.
        if ((byte.load(std::memory_order_relaxed) & part) != part) byte.fetch_or(part, std::memory_order_relaxed);
      }
  }
  Bits operator[](std::uint64_t streamline) const {
    const std::uint8_t* at = bytes_.get() + streamline * stride_;
    Bits regions = 0;
    for (std::size_t b = 0; b < stride_; ++b) regions |= Bits(at[b]) << (8 * b);
    return regions;
  }
  // fn(streamline, regions) for each streamline with a hit, in order; eight bytes at a time past those without
  // (most of them, in a small selection).
  template <typename Fn>
  void for_each(std::uint64_t streamlines, Fn&& fn) const {
    if (stride_ == 1) {  // most selections: a byte a streamline, no division
      for_each_nonzero_chunk(bytes_.get(), streamlines, [&](std::uint64_t first) {
        for (std::uint64_t s = first; s < std::min(streamlines, first + 8); ++s)
          if (bytes_.get()[s] != 0) fn(s, Bits(bytes_.get()[s]));
      });
      return;
    }
    std::uint64_t next = 0;  // the first streamline not yet looked at
    for_each_nonzero_chunk(bytes_.get(), streamlines * stride_, [&](std::uint64_t byte) {
      for (std::uint64_t s = std::max(next, byte / stride_); s <= (byte + 7) / stride_ && s < streamlines; ++s)
        if (const Bits regions = (*this)[s]; regions != 0) fn(s, regions);
      next = std::max(next, (byte + 7) / stride_ + 1);
    });
  }
  // A streamline's bytes on their way to the cache before add() needs them: the locked OR of add() waits for its
  // line, and one add after another would wait for one line after another.
  void prefetch(std::uint64_t streamline) const { __builtin_prefetch(bytes_.get() + streamline * stride_, 1, 1); }

 private:
  struct Free {
    void operator()(std::uint8_t* p) const { std::free(p); }
  };
  std::size_t stride_;
  std::unique_ptr<std::uint8_t, Free> bytes_;
};

// The quanta of a packed voxel's axes (spec §5.4) that decode inside one region's reach: a point with a quantum
// outside them is outside the region, which three integer compares tell before any decoding or exact test.
struct QuantumWindow {
  std::array<std::uint32_t, 3> first{}, span{};  // q is in when q - first <= span (unsigned)

  bool holds(std::uint32_t w) const {
    return (w & kPackedAxisMask) - first[0] <= span[0] && ((w >> 10) & kPackedAxisMask) - first[1] <= span[1] &&
           ((w >> 20) & kPackedAxisMask) - first[2] <= span[2];
  }
};

// decode_axis grows with q (lo + q * step, step >= 0, each step rounded as decode rounds it), so the window is
// found by bisection; a voxel whose bounds make it shrink (a damaged table) gets every quantum.
QuantumWindow quantum_window(const VertexPacker& packer, const std::array<float, 6>& reach) {
  QuantumWindow window;
  for (int c = 0; c < 3; ++c) {
    const float low = packer.decode_axis(c, 0), high = packer.decode_axis(c, kPackedSteps);
    if (!(low <= high) || !std::isfinite(low) || !std::isfinite(high)) {
      window.first[c] = 0, window.span[c] = kPackedSteps;
      continue;
    }
    // The first quantum whose coordinate passes `below` (kPackedSteps + 1 when none does).
    auto first_where = [&](auto below) {
      std::uint32_t lo = 0, hi = kPackedSteps + 1;
      while (lo < hi) {
        const std::uint32_t mid = (lo + hi) / 2;
        if (below(packer.decode_axis(c, mid)))
          lo = mid + 1;
        else
          hi = mid;
      }
      return lo;
    };
    const std::uint32_t first = first_where([&](float x) { return x < reach[c]; });
    const std::uint32_t end = first_where([&](float x) { return x <= reach[3 + c]; });
    if (end <= first)  // none: an empty window
      window.first[c] = kPackedSteps + 1, window.span[c] = 0;
    else
      window.first[c] = first, window.span[c] = end - 1 - first;
  }
  return window;
}

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

  // Where a voxline's test starts, for both tests below: the regions still `open` for its streamline that its
  // points can hit, less those decided without them (a region holding the whole voxel, or the voxline's box:
  // `box_holds`), and the first point to read.
  struct VoxlineTest {
    Bits anywhere = 0, ends = 0;  // left to find at any of its points / at its streamline's end points
    Bits hit = 0;
    std::uint32_t from = 0;
    bool points_needed() const { return (anywhere | ends) != 0; }
    // The regions point i is tested against.
    Bits wanted(const VoxlinePlace& v, std::uint32_t i) const {
      Bits test = anywhere & ~hit;
      if ((i == 0 && v.first_of_streamline) || (i + 1 == v.own && !v.connected)) test |= ends & ~hit;
      return test;
    }
  };
  VoxlineTest begin_test(const VoxlinePlace& v, Bits open, Bits box_holds) {
    VoxlineTest t;
    const Bits touching = voxel_regions.touching[v.voxel] & open;
    const Bits anywhere = touching & (table.include | table.exclude);
    const Bits at_ends = (v.first_of_streamline || !v.connected) ? touching & table.ends : 0;
    t.from = v.synthetic_first ? 1 : 0;
    if ((anywhere | at_ends) == 0 || t.from >= v.own) return t;  // nothing to test, or only a synthetic point
    // A region holding the whole voxel holds every point tested here (a voxline's end point is a source
    // point: synthetic points are never first or last of a streamline).
    const Bits held = voxel_regions.holding[v.voxel] | box_holds;
    t.hit = (anywhere | at_ends) & held;
    t.anywhere = anywhere & ~held;
    t.ends = at_ends & ~held;
    if (t.points_needed()) points_tested += v.own - t.from;
    return t;
  }

  // Tests one voxline in a voxel the regions may touch against those regions still `open` for its
  // streamline; returns the regions holding one of its points.
  Bits test_voxline(const VoxlinePlace& v, Bits open) {
    VoxlineTest t = begin_test(v, open, 0);
    if (!t.points_needed()) return t.hit;
    xyz.resize(3 * std::size_t(v.own));
    file.read_vertices(v.voxel, v.first_vertex, v.own, xyz.data());
    for (std::uint32_t i = t.from; i < v.own; ++i)
      for (Bits b = t.wanted(v, i); b != 0; b &= b - 1) {
        const int r = std::countr_zero(b);
        if (table.regions[r]->contains(&xyz[3 * std::size_t(i)])) t.hit |= Bits(1) << r;
      }
    return t.hit;
  }

  // test_voxline for a voxline of a packed file, read from its words where they lie: a point is decoded and
  // tested only for the regions whose quantum window (windows[r], for v's voxel) holds it, and the voxline's
  // test stops once every region it can still hit has been hit.
  // `box_holds`: regions holding every point the test would read (VoxlineBoxes), hit without reading them.
  Bits test_packed_voxline(const VoxlinePlace& v, Bits open, const VertexPacker& packer,
                           const std::array<QuantumWindow, kMaxRegions>& windows, Bits box_holds = 0) {
    VoxlineTest t = begin_test(v, open, box_holds);
    if (!t.points_needed()) return t.hit;
    const std::uint32_t* words = file.packed_vertices().data() + v.first_vertex;
    for (std::uint32_t i = t.from; i < v.own; ++i) {
      const Bits test = t.wanted(v, i);
      // Nothing left to find but at the last point, for a region that wants ends: straight there.
      if (test == 0) {
        if ((t.ends & ~t.hit) == 0 || v.connected || i + 1 >= v.own) break;
        i = v.own - 2;
        continue;
      }
      float p[3];
      bool decoded = false;
      for (Bits b = test; b != 0; b &= b - 1) {
        const int r = std::countr_zero(b);
        if (!windows[std::size_t(r)].holds(words[i])) continue;
        if (!decoded) packer.decode_word(words[i], p), decoded = true;
        if (table.regions[r]->contains(p)) t.hit |= Bits(1) << r;
      }
    }
    return t.hit;
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

// A boxed voxline's regions: those its box misses (`outside`) and those holding the whole box (`inside`), of the
// regions `candidates` (bit r: windows[r] is region r's window in the voxline's voxel).
struct BoxVerdict {
  Bits outside = 0, inside = 0;
};
BoxVerdict box_verdict(const BoxedVoxline& b, Bits candidates, const RegionTable& table, const VertexPacker& packer,
                       const std::array<QuantumWindow, kMaxRegions>& windows) {
  BoxVerdict verdict;
  if (b.lo[0] > b.hi[0]) return {candidates, 0};  // no point to test
  const std::uint32_t lo_word = b.lo[0] | std::uint32_t(b.lo[1]) << 10 | std::uint32_t(b.lo[2]) << 20;
  const std::uint32_t hi_word = b.hi[0] | std::uint32_t(b.hi[1]) << 10 | std::uint32_t(b.hi[2]) << 20;
  float lo[3], hi[3];
  bool decoded = false;
  for (Bits bits = candidates; bits != 0; bits &= bits - 1) {
    const int r = std::countr_zero(bits);
    const QuantumWindow& w = windows[std::size_t(r)];
    bool misses = false;
    for (int c = 0; c < 3; ++c)  // the box's quanta and the window's do not overlap on axis c
      misses |= b.hi[c] < w.first[c] || b.lo[c] > w.first[c] + w.span[c];
    if (misses) {
      verdict.outside |= Bits(1) << r;
      continue;
    }
    if (!decoded) packer.decode_word(lo_word, lo), packer.decode_word(hi_word, hi), decoded = true;
    // The window is the region's bounding box: a sphere may still miss a box its corners reach into.
    if (!table.regions[r]->may_touch(lo, hi))
      verdict.outside |= Bits(1) << r;
    else if (table.regions[r]->holds_box(lo, hi))
      verdict.inside |= Bits(1) << r;
  }
  return verdict;
}

// One thread's scratch for the voxels it searches.
struct VoxelScratch {
  std::vector<std::uint8_t> ends;
  std::vector<PlacedVoxline> placed;
  std::array<QuantumWindow, kMaxRegions> windows;
};

// How many voxlines ahead a streamline's hit bytes are fetched (RegionHits::prefetch).
constexpr std::size_t kHitsAhead = 16;

// A float a little below (or above) a distance x >= 0 (+infinity included), so that a bound kept in float32 stays a
// bound. The neighbouring float is the next bit pattern (for x >= 0 the rounding never crosses zero), as
// std::nextafter gives it without its library call: a drag calls these for every voxline it looks at.
float float_below(double x) {
  const auto f = static_cast<float>(x);
  return double(f) > x ? std::bit_cast<float>(std::bit_cast<std::uint32_t>(f) - 1) : f;
}
float float_above(double x) {
  const auto f = static_cast<float>(x);
  return double(f) < x ? std::bit_cast<float>(std::bit_cast<std::uint32_t>(f) + 1) : f;
}

// The sphere a drag moves, followed through the distances VoxlineBoxes keeps (near_lo, near_hi): how far it moved
// since a voxel's were measured decides most voxlines; the others are measured again, point by point.
struct DraggedSphere {
  const Region* sphere = nullptr;
  Bits bit = 0;
  double radius = 0, margin = 0;

  DraggedSphere(const RegionTable& table, int region) {
    if (region < 0) return;
    sphere = table.regions[std::size_t(region)];
    bit = Bits(1) << region;
    radius = sphere->radius();
    const Point3f& c = sphere->centre();
    // Far more than the float32 rounding of a distance and of its test (Region's slack, and then some).
    margin = 1e-3 + 1e-6 * (std::abs(c[0]) + std::abs(c[1]) + std::abs(c[2]) + radius);
  }
  struct BoxDistances {
    double nearest = 0, farthest = 0;
  };
  // From the centre to the nearest and the farthest point of b's box (its points' quanta decoded), in mm.
  BoxDistances box_distances(const BoxedVoxline& b, const VertexPacker& packer) const {
    float lo[3], hi[3];
    packer.decode_word(b.lo[0] | std::uint32_t(b.lo[1]) << 10 | std::uint32_t(b.lo[2]) << 20, lo);
    packer.decode_word(b.hi[0] | std::uint32_t(b.hi[1]) << 10 | std::uint32_t(b.hi[2]) << 20, hi);
    const Point3f& c = sphere->centre();
    double near2 = 0, far2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double below = double(lo[a]) - c[a], above = double(c[a]) - hi[a];
      const double gap = std::max({below, above, 0.0});
      const double reach = std::max(std::abs(below), std::abs(above));
      near2 += gap * gap, far2 += reach * reach;
    }
    return {std::sqrt(near2), std::sqrt(far2)};
  }
  // Decides b for the sphere where its distances, `moved` since they were measured (infinite when they never
  // were), allow; else its box's nearest and farthest points (which also tighten its distances); else its points,
  // measured again. The other `candidates` go through box_verdict. Its distances are then from the sphere's centre.
  BoxVerdict decide(BoxedVoxline& b, double moved, Bits candidates, const std::uint32_t* words,
                    const VertexPacker& packer, const RegionTable& table,
                    const std::array<QuantumWindow, kMaxRegions>& windows) const {
    double lo = b.near_lo - moved, hi = b.near_hi + moved;
    BoxVerdict verdict;
    if (lo > radius + margin) {
      verdict.outside = bit;
    } else if (hi < radius - margin) {
      verdict.inside = bit;
    } else if (b.nearest_word != BoxedVoxline::kNoNearest) {  // the point that was nearest, as contains() tests it
      float p[3];
      packer.decode_word(b.nearest_word, p);
      const float d2 = sphere->squared_distance(p);
      if (d2 <= sphere->radius_squared()) verdict.inside = bit;
      hi = std::min(hi, std::sqrt(double(d2)));
    }
    Bits boxed_already = 0;  // the sphere, where its box was measured here: box_verdict would test it again
    if (((verdict.outside | verdict.inside) & bit) == 0 && b.lo[0] <= b.hi[0]) {
      // The box's nearest and farthest points bound the nearest point's distance: kept, they decide this voxline
      // without its points after the next moves too.
      boxed_already = bit;
      const BoxDistances box = box_distances(b, packer);
      lo = std::max(lo, box.nearest);
      hi = std::min(hi, box.farthest);
      if (lo > radius + margin)
        verdict.outside = bit;
      else if (hi < radius - margin)
        verdict.inside = bit;
    }
    if (const Bits rest = candidates & ~(verdict.outside | verdict.inside | boxed_already); rest != 0) {
      const BoxVerdict boxed = box_verdict(b, rest, table, packer, windows);
      verdict.outside |= boxed.outside, verdict.inside |= boxed.inside;
    }
    if (((verdict.outside | verdict.inside) & bit) == 0) {  // measured again, with contains()'s arithmetic
      float nearest = INFINITY;
      std::uint32_t nearest_word = BoxedVoxline::kNoNearest;
      for (std::uint32_t i = (b.flags & BoxedVoxline::kSyntheticFirst) ? 1 : 0; i < b.own; ++i) {
        float p[3];
        const std::uint32_t word = words[b.first + i];
        packer.decode_word(word, p);
        if (const float d2 = sphere->squared_distance(p); d2 < nearest)
          nearest = d2, nearest_word = word & BoxedVoxline::kQuantaBits;
      }
      b.nearest_word = nearest_word;
      (nearest <= sphere->radius_squared() ? verdict.inside : verdict.outside) |= bit;
      lo = hi = std::sqrt(double(nearest));
    }
    b.near_lo = float_below(std::max(0.0, lo));
    b.near_hi = float_above(hi);
    return verdict;
  }
};

// A packed voxel's voxlines through their boxes: only those across a region's surface are read point by point, and
// for the dragged sphere only those its move may have carried across.
void boxed_voxel_hits(HitSearch& search, std::uint32_t voxel, const VertexPacker& packer, VoxlineBoxes& boxes,
                      std::span<BoxedVoxline> list, const DraggedSphere& dragged, VoxelScratch& scratch,
                      RegionHits& hits) {
  const Bits touching = search.voxel_regions.touching[voxel];
  const Bits candidates = touching & ~search.voxel_regions.holding[voxel];
  const std::uint64_t first = search.voxels[voxel].vertex_first;
  const std::uint32_t* words = search.file.packed_vertices().data() + first;
  const bool follow = (candidates & dragged.bit) != 0;
  VoxelReference& reference = boxes.reference(voxel);
  double moved = INFINITY;
  if (follow && reference.known) {
    const Point3f& c = dragged.sphere->centre();
    moved = std::hypot(double(c[0]) - reference.centre[0], double(c[1]) - reference.centre[1],
                       double(c[2]) - reference.centre[2]);
  }
  reference.known = reference.known && !follow;  // until every voxline's distances are the new centre's
  for (std::size_t k = 0; k < list.size(); ++k) {
    if (k + kHitsAhead < list.size()) hits.prefetch(list[k + kHitsAhead].streamline);
    BoxedVoxline& b = list[k];
    const BoxVerdict verdict = follow
                                   ? dragged.decide(b, moved, candidates, words, packer, search.table, scratch.windows)
                                   : box_verdict(b, candidates, search.table, packer, scratch.windows);
    if ((touching & ~verdict.outside) == 0) continue;  // outside every region near the voxel
    const VoxlinePlace v{voxel,
                         b.own,
                         (b.flags & BoxedVoxline::kSyntheticFirst) != 0,
                         (b.flags & BoxedVoxline::kFirstOfStreamline) != 0,
                         (b.flags & BoxedVoxline::kLastOfStreamline) == 0,
                         first + b.first};
    if (const Bits hit = search.test_packed_voxline(v, ~verdict.outside, packer, scratch.windows, verdict.inside))
      hits.add(b.streamline, hit);
  }
  if (follow) reference = {dragged.sphere->centre(), true};
}

// A voxel's voxlines placed in its block (`placed`) tested: a packed block's points where they lie, a float32 block's
// read out.
void placed_voxel_hits(HitSearch& search, std::uint32_t voxel, const VertexPacker* packer,
                       std::span<const PlacedVoxline> placed, VoxelScratch& scratch, RegionHits& hits) {
  for (std::size_t k = 0; k < placed.size(); ++k) {
    if (k + kHitsAhead < placed.size()) hits.prefetch(placed[k + kHitsAhead].streamline);
    const PlacedVoxline& p = placed[k];
    const VoxlinePlace v{voxel, p.own, p.synthetic_first, p.first_of_streamline, !p.last_of_streamline, p.first_vertex};
    const Bits hit =
        packer ? search.test_packed_voxline(v, ~Bits(0), *packer, scratch.windows) : search.test_voxline(v, ~Bits(0));
    if (hit != 0) hits.add(p.streamline, hit);
  }
}

// Only the voxels the regions may touch, through their lists (VoxelVoxlines): a voxel's list, placed in its
// block (place_voxel_voxlines, or kept boxed by `boxes` between selections), is all a voxline costs; with `level`,
// only that level's voxlines, placed already. Voxels are independent here, so they are searched side by side (the
// first error in voxel order reported).
void hits_by_index(HitSearch& q, const VoxelVoxlines* index, RegionHits& hits, std::uint64_t& bytes_read,
                   VoxlineBoxes* boxes, const LevelVoxlines* level) {
  std::vector<std::uint32_t> touched;
  for (std::size_t voxel = 0; voxel < q.voxels.size(); ++voxel)
    if (q.voxel_regions.touching[voxel] != 0) touched.push_back(std::uint32_t(voxel));
  const bool packed = q.file.position_encoding() == PositionEncoding::Packed;
  // The first sphere among the includes and excludes is the one a drag moves, as far as the boxes know.
  int sphere = -1;
  for (std::size_t r = 0; r < q.table.regions.size() && sphere < 0; ++r)
    if (q.table.regions[r]->shape() == Region::Shape::Sphere && ((q.table.include | q.table.exclude) >> r & 1))
      sphere = int(r);
  if (boxes) {
    boxes->track_region(sphere);
    boxes->selection_started();
  }
  const DraggedSphere dragged(q.table, sphere);
  std::vector<HitSearch> per_thread(resolve_threads(0), q);
  std::vector<VoxelScratch> scratch(per_thread.size());
  // A query touching most voxels reads most blocks: their pages are let go as it goes (walk_streamlines does so too);
  // a level's voxlines are a small part of each block.
  std::atomic<std::uint64_t> read_since_release = 0;
  parallel_for_first_error_in_order(touched.size(), unsigned(per_thread.size()), [&](std::uint64_t k, unsigned t) {
    const std::uint32_t voxel = touched[k];
    if (!level && read_since_release.fetch_add(4ull * q.voxels[voxel].vertex_count) > (64ull << 20)) {
      read_since_release = 0;
      q.file.release_resident_pages();
    }
    // The voxel's voxlines placed in its block: the level's, or its list's (place_voxel_voxlines).
    const auto placed = [&]() -> std::span<const PlacedVoxline> {
      if (level) return level->of_voxel(voxel);
      place_voxel_voxlines(q.file, *index, voxel, scratch[t].ends, scratch[t].placed);
      return scratch[t].placed;
    };
    if (!packed) return placed_voxel_hits(per_thread[t], voxel, nullptr, placed(), scratch[t], hits);
    const VertexPacker packer(q.voxels[voxel]);
    for (Bits b = q.voxel_regions.touching[voxel]; b != 0; b &= b - 1) {
      const int r = std::countr_zero(b);
      scratch[t].windows[std::size_t(r)] = quantum_window(packer, q.table.reach[std::size_t(r)]);
    }
    if (boxes)
      if (const std::optional<std::span<BoxedVoxline>> list = boxes->voxel(voxel, *index))
        return boxed_voxel_hits(per_thread[t], voxel, packer, *boxes, *list, dragged, scratch[t], hits);
    placed_voxel_hits(per_thread[t], voxel, &packer, placed(), scratch[t], hits);
  });
  for (std::size_t k = 0; k < touched.size() && !level; ++k) {
    // The list, and the block's voxline ends: its packed words (float32: order 0), read whole.
    const VoxelEntry& v = q.voxels[touched[k]];
    bytes_read +=
        index->of_voxel(touched[k]).size_bytes() +
        (packed ? 4ull * v.vertex_count : order_array_bytes(v.segment_count, q.file.order(touched[k], 0).bits));
  }
  for (const HitSearch& search : per_thread) q.points_tested += search.points_tested;
}

// Everything select_streamlines decides but the level; with `level`, among that level's voxlines alone.
SelectionResult select_by_regions_and_lengths(const VxlFile& file, const SelectionCriteria& criteria,
                                              const VoxelVoxlines* index, SelectionPath path, VoxlineBoxes* boxes,
                                              const LevelVoxlines* level) {
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
  RegionHits hits(n, table.regions.size());
  if (index || level) {
    if (file.position_encoding() != PositionEncoding::Packed || level) boxes = nullptr;
    hits_by_index(search, index, hits, result.bytes_read, boxes, level);
    if (boxes) boxes->selection_done();
  } else
    hits_by_scan(search, hits, result.bytes_read);
  result.points_tested = search.points_tested;

  const Bits needed = table.include | table.ends;
  const std::uint64_t vertex_bytes = file.position_encoding() == PositionEncoding::Packed ? 4 : 12;
  result.bytes_read += result.points_tested * vertex_bytes;
  result.streamlines_per_region.assign(table.regions.size(), 0);
  auto count_regions = [&](Bits regions) {
    for (Bits b = regions; b != 0; b &= b - 1) ++result.streamlines_per_region[std::countr_zero(b)];
  };
  // Length limits, for the streamlines still in (tckedit applies its thresholds even without options: a header
  // can make them cut).
  const LengthLimits limits = tckedit_length_limits(file, criteria.min_length, criteria.max_length);
  if (limits.keep_every_length() && !criteria.invert && needed != 0) {
    // The streamlines kept are those whose hits pass, in order, and they have points: no table of the rest.
    hits.for_each(n, [&](std::uint64_t s, Bits regions) {
      count_regions(regions);
      if ((regions & needed) == needed && (regions & table.exclude) == 0) result.streamlines.push_back(s);
    });
    return result;
  }
  std::vector<std::uint8_t> passes(n, needed == 0 ? 1 : 0);
  hits.for_each(n, [&](std::uint64_t s, Bits regions) {
    passes[s] = (regions & needed) == needed && (regions & table.exclude) == 0;
    count_regions(regions);
  });
  // SLEN decides a packed file's lengths: its points are not the source's, and SLEN is within (points + 5) float32
  // roundings of tckedit's length. With float32 positions SLEN decides where it lies farther than that from both
  // limits, and the points of the rest are measured as tckedit measures them, so the answer is tckedit's to the
  // bit. Files without SLEN, and the table-walking path, measure every length.
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
  // A streamline that passes by a point in a region has points: only the others are looked up in STRM.
  const std::span<const std::uint64_t> first_voxline = file.streamline_first_voxline();
  const bool passing_have_points = !criteria.invert && needed != 0;
  auto keep_from = [&](std::uint64_t first, std::uint64_t end) {
    for (std::uint64_t s = first; s < end; ++s)
      if ((passes[s] != 0) != criteria.invert && (passing_have_points || first_voxline[s + 1] != first_voxline[s]))
        result.streamlines.push_back(s);
  };
  if (criteria.invert)
    keep_from(0, n);
  else  // only the streamlines that pass: eight at a time past the others
    for_each_nonzero_chunk(passes.data(), n, [&](std::uint64_t s) { keep_from(s, std::min(n, s + 8)); });
  return result;
}

}  // namespace

void read_ahead_selection_tables(const VxlFile& file) {
  const bool indexed = file.find_section(section_id("VXIX")) != nullptr;
  for (const std::uint32_t id :
       {section_id("VOXT"), section_id("STRM"), indexed ? section_id("VXIX") : section_id("VXLN"), section_id("SLEN")})
    if (const SectionEntry* e = file.find_section(id)) file.will_need(e->offset, e->size);
}

void check_level(const std::string& path, std::uint32_t level, std::uint32_t levels) {
  if (level >= levels)
    throw Error(ErrorKind::Usage, "--level", std::nullopt,
                path + " has " + std::to_string(levels) + " level" + (levels == 1 ? "" : "s") + " of detail: 0 to " +
                    std::to_string(levels - 1));
}

SelectionResult select_streamlines(const VxlFile& file, const SelectionCriteria& criteria, const VoxelVoxlines* index,
                                   SelectionPath path, VoxlineBoxes* boxes, const LevelVoxlines* level_voxlines) {
  if (criteria.min_length && criteria.max_length && *criteria.min_length > *criteria.max_length)
    throw Error(ErrorKind::Usage, "--min-length", std::nullopt, "the minimum length is above the maximum length");
  if (criteria.level) check_level(file.path(), *criteria.level, file.level_count());
  if (level_voxlines && (!criteria.level || level_voxlines->level() != *criteria.level))
    throw std::logic_error("select_streamlines: the level's voxlines are not those of the criteria's level");
  SelectionResult result = select_by_regions_and_lengths(file, criteria, index, path, boxes,
                                                         path == SelectionPath::Fastest ? level_voxlines : nullptr);
  if (criteria.level) {
    const std::uint32_t levels = file.level_count();
    std::erase_if(result.streamlines, [&](std::uint64_t s) { return streamline_depth(s, levels) < *criteria.level; });
  }
  return result;
}

}  // namespace vxl
