#include "converter/convert/voxel_table.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "format/base/error.h"
#include "format/streamline_length.h"

namespace vxl::detail {
namespace {

std::string format_mm(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v;
  return s.str();
}

[[noreturn]] void fail_non_finite(const std::string& path, std::uint64_t streamline, std::uint64_t point) {
  throw Error(
      ErrorKind::Input, path, std::nullopt,
      "non-finite coordinate in streamline " + std::to_string(streamline) + " (point " + std::to_string(point) + ")");
}

[[noreturn]] void fail_long_voxline(const std::string& path) {
  throw Error(ErrorKind::Unsupported, path, std::nullopt,
              "a voxline of more than 2^31-1 points; use a smaller --voxel-size");
}

// The one way both find tight bounds: widen [lo, hi] to `count` points (xyz). Six named locals, not the arrays:
// stored through pointers, the compiler would have to assume they alias the points, and indexed in a loop over
// the axes it kept them on the stack, stored and reloaded at every point (twice the time).
inline void widen(float lo[3], float hi[3], const float* xyz, std::uint64_t count) {
  float lx = lo[0], ly = lo[1], lz = lo[2], hx = hi[0], hy = hi[1], hz = hi[2];
  for (const float* p = xyz; p != xyz + 3 * count; p += 3) {
    lx = std::min(lx, p[0]), ly = std::min(ly, p[1]), lz = std::min(lz, p[2]);
    hx = std::max(hx, p[0]), hy = std::max(hy, p[1]), hz = std::max(hz, p[2]);
  }
  lo[0] = lx, lo[1] = ly, lo[2] = lz, hi[0] = hx, hi[1] = hy, hi[2] = hz;
}

// ... and store them: a zero bound as +0 whichever zero came first (-0 + 0 = +0).
inline void store_tight_bounds(const float lo[3], const float hi[3], VoxelEntry& v) {
  for (int c = 0; c < 3; ++c) {
    v.tight_min[c] = lo[c] + 0.0f;
    v.tight_max[c] = hi[c] + 0.0f;
  }
}

}  // namespace

void BoundsScan::add(const float* pts, const std::uint64_t* offsets, std::uint64_t first, std::uint64_t end,
                     std::uint64_t index_base, float* lengths) {
  // Locals, not the fields: the compiler cannot tell that `this` does not alias the points. Each streamline in
  // three short loops (finite, bounds, steps) over points in cache: together in one, the compiler shuffled the
  // bounds through vector registers at every point.
  float l[3] = {lo[0], lo[1], lo[2]}, h[3] = {hi[0], hi[1], hi[2]};
  double step2 = longest_step2;
  std::uint64_t step2_sum = step2_sum_fixed, step_count = steps;
  for (std::uint64_t k = first; k < end && bad_streamline == kNone; ++k) {
    const float* const points = pts + 3 * offsets[k];
    const std::uint64_t n = offsets[k + 1] - offsets[k];
    for (std::uint64_t i = 0; i < n; ++i) {
      const float* p = points + 3 * i;
      if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
        bad_streamline = index_base + k;
        bad_point = i;
        break;
      }
    }
    if (bad_streamline != kNone) break;  // its bounds and length are moot: the conversion fails
    widen(l, h, points, n);              // in float: converting to double afterwards gives the same bounds
    for (std::uint64_t i = 1; i < n; ++i) {
      const float* p = points + 3 * i;
      const double dx = double(p[0]) - p[-3], dy = double(p[1]) - p[-2], dz = double(p[2]) - p[-1];
      const double d2 = dx * dx + dy * dy + dz * dz;
      step2 = std::max(step2, d2);
      // Signed: the same value (at most 2^30), without the branch an unsigned conversion takes.
      step2_sum += static_cast<std::uint64_t>(static_cast<std::int64_t>(std::min(d2, 0x1p20) * 1024.0));
    }
    step_count += n > 0 ? n - 1 : 0;
    // While its points are in cache.
    if (lengths) lengths[k] = stored_length_of({points, std::size_t(3 * n)});
  }
  std::copy(l, l + 3, lo);
  std::copy(h, h + 3, hi);
  step2_sum_fixed = step2_sum;
  steps = step_count;
  longest_step2 = step2;
}

void BoundsScan::merge(const BoundsScan& later) {
  for (int c = 0; c < 3; ++c) {
    lo[c] = std::min(lo[c], later.lo[c]);
    hi[c] = std::max(hi[c], later.hi[c]);
  }
  longest_step2 = std::max(longest_step2, later.longest_step2);
  step2_sum_fixed += later.step2_sum_fixed;
  steps += later.steps;
  if (bad_streamline == kNone) {
    bad_streamline = later.bad_streamline;
    bad_point = later.bad_point;
  }
}

void BoundsScan::check(const std::string& path) const {
  if (bad_streamline != kNone) fail_non_finite(path, bad_streamline, bad_point);
}

void check_voxel_size(double s, const std::string& path) {
  if (!std::isfinite(s) || !(s > 0))
    throw Error(ErrorKind::Usage, path, std::nullopt, "voxel size must be a positive number of mm");
}

Grid set_grid(MetaSection& m, const double lo[3], const double hi[3], const std::string& path) {
  const double s = m.voxel_size;
  for (int c = 0; c < 3; ++c) {
    double cells = std::floor((hi[c] - lo[c]) / s) + 1;
    if (!(cells < double(std::numeric_limits<std::int32_t>::max()))) {
      double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
      throw Error(ErrorKind::Unsupported, path, std::nullopt,
                  "a voxel size of " + format_mm(s) +
                      " mm makes a grid of more than 2^31 voxels along an axis (extent " + format_mm(extent) +
                      " mm); use --voxel-size " + format_mm(extent / 1e9) + " or larger");
    }
    m.grid_dims[c] = static_cast<std::int32_t>(cells);
    // A zero as +0 whichever zero came first (-0 + 0 = +0), as for the tight bounds: the bytes depend on the
    // points, not on their order.
    m.grid_origin[c] = lo[c] + 0.0;
    m.bounds_min[c] = lo[c] + 0.0;
    m.bounds_max[c] = hi[c] + 0.0;
  }
  return Grid{{m.grid_origin[0], m.grid_origin[1], m.grid_origin[2]}, s};
}

void check_level_count(std::uint32_t levels, const std::string& path) {
  if (levels < 1 || levels > kMaxLevels)
    throw Error(ErrorKind::Usage, path, std::nullopt,
                "levels of detail must be 1.." + std::to_string(kMaxLevels) + ", not " + std::to_string(levels));
}

void fail_too_many_synthetic(const std::string& path, double s, double longest_step2, std::uint64_t synthetic_limit) {
  throw Error(ErrorKind::Unsupported, path, std::nullopt,
              "voxel size " + format_mm(s) + " mm is far below the longest step (" +
                  format_mm(std::sqrt(longest_step2)) + " mm): splitting steps at voxel faces would add more than " +
                  std::to_string(synthetic_limit) + " points (one per source point, and 4096 more); use --voxel-size " +
                  format_mm(std::sqrt(longest_step2)) + " or larger");
}

void count_voxel_use(std::span<const TempVoxline> streamline, std::uint32_t depth, VoxelUse& use,
                     const std::string& path) {
  for (std::size_t j = 0; j < streamline.size(); ++j) {
    const TempVoxline& v = streamline[j];
    const std::uint64_t own = v.own();
    if (own > kVoxlineCountMask) fail_long_voxline(path);
    const std::uint64_t used = own + (j + 1 < streamline.size() ? 1 : 0);  // + the connecting vertex
    use.vertices[std::size_t(v.voxel) * use.levels + depth] += used;
    use.segments[std::size_t(v.voxel) * use.levels + depth] += used - 1;
  }
}

VoxelTable build_voxel_table(std::span<LocalVoxels> indexes, std::uint32_t level_count, MetaSection& m,
                             const std::string& path) {
  std::vector<Coord> all;
  for (const LocalVoxels& x : indexes) all.insert(all.end(), x.coords->begin(), x.coords->end());
  std::sort(all.begin(), all.end(), zyx_less);
  all.erase(std::unique(all.begin(), all.end()), all.end());
  const std::size_t n = all.size();
  if (n >= std::uint64_t(std::numeric_limits<std::int32_t>::max()))
    throw Error(ErrorKind::Unsupported, path, std::nullopt,
                "more than 2^31 non-empty voxels; use a larger --voxel-size than " + format_mm(m.voxel_size));

  // Counts per (voxel, depth), then per voxel.
  const std::uint32_t levels = level_count;
  std::vector<std::uint64_t> depth_vertices(n * levels, 0), depth_segments(n * levels, 0);
  for (LocalVoxels& x : indexes) {
    if (x.use->levels != levels) throw std::logic_error("build_voxel_table: VoxelUse has another level count");
    const std::vector<Coord>& coords = *x.coords;
    x.global_id.resize(coords.size());
    for (std::size_t i = 0; i < coords.size(); ++i) {
      const auto g =
          static_cast<std::uint32_t>(std::lower_bound(all.begin(), all.end(), coords[i], zyx_less) - all.begin());
      x.global_id[i] = g;
      for (std::uint32_t d = 0; d < levels; ++d) {
        depth_vertices[std::size_t(g) * levels + d] += x.use->vertices[i * levels + d];
        depth_segments[std::size_t(g) * levels + d] += x.use->segments[i * levels + d];
      }
    }
  }

  VoxelTable table;
  table.voxels.resize(n);
  table.levels.resize(n * (levels - 1));
  std::uint64_t vertex_total = 0, segment_total = 0;
  for (std::size_t g = 0; g < n; ++g) {
    // Level d's prefix: the voxlines of depth >= d (vxl_levels.h), summed from the deepest.
    std::uint64_t vertices = 0, segments = 0;
    for (std::uint32_t d = levels; d-- > 0;) {
      vertices += depth_vertices[g * levels + d];
      segments += depth_segments[g * levels + d];
      if (vertices > std::numeric_limits<std::uint32_t>::max())
        throw Error(
            ErrorKind::Unsupported, path, std::nullopt,
            "a voxel holds more than 2^32-1 vertices; use a --voxel-size smaller than " + format_mm(m.voxel_size));
      if (d > 0)
        table.levels[g * (levels - 1) + d - 1] = {static_cast<std::uint32_t>(vertices),
                                                  static_cast<std::uint32_t>(segments)};
    }
    VoxelEntry& v = table.voxels[g];
    v = {};
    v.coord[0] = all[g].x;
    v.coord[1] = all[g].y;
    v.coord[2] = all[g].z;
    v.vertex_first = vertex_total;
    v.vertex_count = static_cast<std::uint32_t>(vertices);
    v.segment_count = static_cast<std::uint32_t>(segments);
    vertex_total += vertices;
    segment_total += segments;
  }
  // Inside each block, depth by depth from the deepest; within a depth each index writes after the
  // indexes before it: streamline order is kept.
  std::vector<std::uint64_t>& next = depth_vertices;  // reused: the counts are no longer needed
  for (std::size_t g = 0; g < n; ++g) {
    const std::span<const LevelEntry> row(table.levels.data() + g * (levels - 1), levels - 1);
    for (std::uint32_t d = 0; d < levels; ++d)
      next[g * levels + d] = table.voxels[g].vertex_first + depth_first_vertex(row, d);
  }
  for (LocalVoxels& x : indexes) {
    x.cursor.resize(x.global_id.size() * levels);
    for (std::size_t i = 0; i < x.global_id.size(); ++i)
      for (std::uint32_t d = 0; d < levels; ++d) {
        x.cursor[i * levels + d] = next[std::size_t(x.global_id[i]) * levels + d];
        next[std::size_t(x.global_id[i]) * levels + d] += x.use->vertices[i * levels + d];
      }
  }
  m.voxel_count = static_cast<std::uint32_t>(n);
  m.vertex_count = vertex_total;
  m.segment_count = segment_total;
  m.level_count = levels > 1 && n > 0 ? levels : 0;  // LODS exactly when level_count > 1 (spec §5.12)
  return table;
}

void set_tight_bounds(std::span<VoxelEntry> voxels, const float* vertices, std::uint64_t vertex_base) {
  for (VoxelEntry& v : voxels) {
    const float* p = vertices + 3 * (v.vertex_first - vertex_base);
    float lo[3] = {p[0], p[1], p[2]}, hi[3] = {p[0], p[1], p[2]};
    widen(lo, hi, p + 3, v.vertex_count > 0 ? v.vertex_count - 1 : 0);
    store_tight_bounds(lo, hi, v);
  }
}

void VoxelBounds::grow_to(std::size_t voxels) {
  if (lo_.size() >= 3 * voxels) return;
  lo_.resize(3 * voxels, INFINITY);
  hi_.resize(3 * voxels, -INFINITY);
}

void VoxelBounds::add(std::uint32_t local, const float* xyz, std::uint64_t count) {
  float* const lo_out = lo_.data() + 3 * std::size_t(local);
  float* const hi_out = hi_.data() + 3 * std::size_t(local);
  float lo[3] = {lo_out[0], lo_out[1], lo_out[2]}, hi[3] = {hi_out[0], hi_out[1], hi_out[2]};
  widen(lo, hi, xyz, count);
  std::copy(lo, lo + 3, lo_out);
  std::copy(hi, hi + 3, hi_out);
}

void VoxelBounds::add_voxline(std::span<const TempVoxline> streamline, std::size_t j, const float* pts,
                              const float* synthetic_xyz) {
  const std::uint32_t local = streamline[j].voxel;
  for_each_voxline_run(streamline, j, pts, synthetic_xyz,
                       [&](const float* xyz, std::uint64_t count) { add(local, xyz, count); });
}

void VoxelBounds::merge(std::uint32_t local, const VoxelBounds& other, std::uint32_t other_local) {
  add(local, other.lo_.data() + 3 * std::size_t(other_local), 1);
  add(local, other.hi_.data() + 3 * std::size_t(other_local), 1);
}

void VoxelBounds::set_tight_bounds(std::uint32_t local, VoxelEntry& v) const {
  store_tight_bounds(lo_.data() + 3 * std::size_t(local), hi_.data() + 3 * std::size_t(local), v);
}

}  // namespace vxl::detail
