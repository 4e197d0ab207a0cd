#include "voxelize.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "error.h"
#include "voxelize_streamline.h"

namespace vxl {

unsigned resolve_threads(unsigned requested) {
  if (requested > 0) return requested;
  unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : n;
}

namespace {

using detail::Coord;
using detail::Grid;
using detail::kNoSynthetic;
using detail::TempVoxline;
using detail::VoxelIndex;
using detail::voxelize_streamline;
using detail::zyx_less;

// One thread's contiguous range of streamlines.
struct Chunk {
  std::uint64_t first_streamline = 0, end_streamline = 0;
  VoxelIndex index;
  std::vector<TempVoxline> voxlines;
  std::vector<std::uint64_t> first_voxline;  // per streamline of the chunk, chunk-local
  std::vector<float> synthetic_xyz;
  std::vector<double> synthetic_t;  // per synthetic point: where it lies on its step, for value interpolation
  std::vector<std::uint64_t> vertices_per_voxel;  // by local id
  std::vector<std::uint64_t> segments_per_voxel;  // by local id
  std::vector<std::uint32_t> global_id;     // local id -> global voxel index
  std::vector<std::uint64_t> cursor;        // local id -> next vertex to write (global index)
  std::uint64_t voxline_base = 0;           // first global voxline of this chunk
  bool too_many_synthetic = false;
};

// Splits [0, N) into `parts` contiguous ranges of about equal point counts.
std::vector<std::uint64_t> split_by_points(const std::vector<std::uint64_t>& offsets, unsigned parts) {
  const std::uint64_t n = offsets.size() - 1, total = offsets.back();
  std::vector<std::uint64_t> bounds = {0};
  for (unsigned k = 1; k < parts; ++k) {
    std::uint64_t target = total / parts * k;
    auto it = std::lower_bound(offsets.begin(), offsets.end(), target);
    std::uint64_t s = std::min<std::uint64_t>(n, static_cast<std::uint64_t>(it - offsets.begin()));
    bounds.push_back(std::max(bounds.back(), s));
  }
  bounds.push_back(n);
  return bounds;
}

template <typename F>
void parallel_for_chunks(std::size_t count, unsigned threads, F&& body) {
  if (threads <= 1 || count <= 1) {
    for (std::size_t i = 0; i < count; ++i) body(i);
    return;
  }
  std::vector<std::thread> pool;
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  for (unsigned t = 0; t < std::min<std::size_t>(threads, count); ++t)
    pool.emplace_back([&] {
      for (std::size_t i; (i = next++) < count;) {
        try {
          body(i);
        } catch (...) {
          std::lock_guard lock(error_mutex);
          if (!error) error = std::current_exception();
        }
      }
    });
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
}

std::string format_mm(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v;
  return s.str();
}

// Bounds, finiteness and the longest step (for the suggestion when long steps explode) of one range of
// streamlines.
struct BoundsPart {
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double longest_step2 = 0;
  std::uint64_t bad_streamline = std::numeric_limits<std::uint64_t>::max(), bad_point = 0;  // first non-finite
};

void scan_bounds(const float* pts, const std::vector<std::uint64_t>& offsets, std::uint64_t first, std::uint64_t end,
                 BoundsPart& b) {
  // Locals, not b's fields: the compiler cannot tell that b does not alias the points.
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double longest_step2 = 0;
  for (std::uint64_t k = first; k < end && b.bad_streamline == std::numeric_limits<std::uint64_t>::max(); ++k) {
    for (std::uint64_t i = offsets[k]; i < offsets[k + 1]; ++i) {
      const float* p = pts + 3 * i;
      if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
        b.bad_streamline = k;
        b.bad_point = i - offsets[k];
        break;
      }
      for (int c = 0; c < 3; ++c) {  // in float: converting to double afterwards gives the same bounds
        lo[c] = std::min(lo[c], p[c]);
        hi[c] = std::max(hi[c], p[c]);
      }
      if (i > offsets[k]) {
        double d2 = 0;
        for (int c = 0; c < 3; ++c) d2 += (double(p[c]) - p[c - 3]) * (double(p[c]) - p[c - 3]);
        longest_step2 = std::max(longest_step2, d2);
      }
    }
  }
  std::copy(lo, lo + 3, b.lo);
  std::copy(hi, hi + 3, b.hi);
  b.longest_step2 = longest_step2;
}

}  // namespace

namespace detail {

void check_voxel_size(double s, const std::string& path) {
  if (!std::isfinite(s) || !(s > 0)) throw Error(ErrorKind::Usage, path, std::nullopt, "voxel size must be a positive number of mm");
}

void fail_non_finite(const std::string& path, std::uint64_t streamline, std::uint64_t point) {
  throw Error(ErrorKind::Input, path, std::nullopt,
              "non-finite coordinate in streamline " + std::to_string(streamline) + " (point " + std::to_string(point) + ")");
}

Grid set_grid(MetaSection& m, const double lo[3], const double hi[3], const std::string& path) {
  const double s = m.voxel_size;
  for (int c = 0; c < 3; ++c) {
    double cells = std::floor((hi[c] - lo[c]) / s) + 1;
    if (!(cells < double(std::numeric_limits<std::int32_t>::max()))) {
      double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
      throw Error(ErrorKind::Unsupported, path, std::nullopt,
                  "a voxel size of " + format_mm(s) + " mm makes a grid of more than 2^31 voxels along an axis (extent " +
                      format_mm(extent) + " mm); use --voxel-size " + format_mm(extent / 1e9) + " or larger");
    }
    m.grid_dims[c] = static_cast<std::int32_t>(cells);
    m.grid_origin[c] = lo[c];
    m.bounds_min[c] = lo[c];
    m.bounds_max[c] = hi[c];
  }
  return Grid{{lo[0], lo[1], lo[2]}, s};
}

void fail_too_many_synthetic(const std::string& path, double s, double longest_step2) {
  throw Error(ErrorKind::Unsupported, path, std::nullopt,
              "voxel size " + format_mm(s) + " mm is far below the longest step (" + format_mm(std::sqrt(longest_step2)) +
                  " mm): splitting steps at voxel faces would more than double the points; use --voxel-size " +
                  format_mm(std::sqrt(longest_step2)) + " or larger");
}

void fail_long_voxline(const std::string& path) {
  throw Error(ErrorKind::Unsupported, path, std::nullopt, "a voxline of more than 2^31-1 points; use a smaller --voxel-size");
}

void check_voxel_total(std::uint64_t n_voxels, double s, const std::string& path) {
  if (n_voxels >= std::uint64_t(std::numeric_limits<std::int32_t>::max()))
    throw Error(ErrorKind::Unsupported, path, std::nullopt,
                "more than 2^31 non-empty voxels; use a larger --voxel-size than " + format_mm(s));
}

void fail_full_voxel(const std::string& path, double s) {
  throw Error(ErrorKind::Unsupported, path, std::nullopt,
              "a voxel holds more than 2^32-1 vertices; use a --voxel-size smaller than " + format_mm(s));
}

}  // namespace detail

struct VoxelPlan::Work {
  unsigned threads = 1;
  std::vector<Chunk> chunks;
};

VoxelPlan::VoxelPlan() : work_(std::make_unique<Work>()) {}
VoxelPlan::VoxelPlan(VoxelPlan&&) noexcept = default;
VoxelPlan& VoxelPlan::operator=(VoxelPlan&&) noexcept = default;
VoxelPlan::~VoxelPlan() = default;

VoxelPlan plan_voxels(const Tractogram& t, const VoxelizeSettings& settings) {
  const std::string& path = t.source.path;
  const double s = settings.voxel_size;
  detail::check_voxel_size(s, path);
  const unsigned threads = resolve_threads(settings.threads);
  const std::uint64_t n_streamlines = t.streamline_count(), n_points = t.point_count();
  const float* pts = t.positions.data();

  VoxelPlan plan;
  plan.work_->threads = threads;
  MetaSection& m = plan.meta_;
  m.streamline_count = n_streamlines;
  m.point_count = n_points;
  m.voxel_size = s;

  // The same streamline ranges serve the bounds scan and pass 1.
  const std::vector<std::uint64_t> bounds = split_by_points(t.offsets, threads);
  std::vector<BoundsPart> parts(bounds.size() - 1);
  parallel_for_chunks(parts.size(), threads, [&](std::size_t c) { scan_bounds(pts, t.offsets, bounds[c], bounds[c + 1], parts[c]); });
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double longest_step2 = 0;
  for (const BoundsPart& b : parts) {
    if (b.bad_streamline != std::numeric_limits<std::uint64_t>::max())  // the first one in streamline order
      detail::fail_non_finite(path, b.bad_streamline, b.bad_point);
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], double(b.lo[c]));
      hi[c] = std::max(hi[c], double(b.hi[c]));
    }
    longest_step2 = std::max(longest_step2, b.longest_step2);
  }
  if (n_points == 0) return plan;  // no voxels; place_vertices fills STRM with zeros
  const Grid grid = detail::set_grid(m, lo, hi, path);

  // Pass 1: voxlines per chunk of streamlines, then each chunk's vertex and segment count per voxel.
  std::vector<Chunk>& chunks = plan.work_->chunks;
  chunks.resize(bounds.size() - 1);
  parallel_for_chunks(chunks.size(), threads, [&](std::size_t c) {
    Chunk& ch = chunks[c];
    ch.first_streamline = bounds[c];
    ch.end_streamline = bounds[c + 1];
    std::uint64_t chunk_points = t.offsets[ch.end_streamline] - t.offsets[ch.first_streamline];
    ch.voxlines.reserve(chunk_points / 4 + 16);
    ch.first_voxline.reserve(ch.end_streamline - ch.first_streamline + 1);
    std::uint64_t limit = static_cast<std::uint64_t>(settings.max_synthetic_per_point * double(chunk_points)) + 4096;
    for (std::uint64_t k = ch.first_streamline; k < ch.end_streamline; ++k) {
      ch.first_voxline.push_back(ch.voxlines.size());
      voxelize_streamline(grid, pts, t.offsets[k], t.offsets[k + 1] - t.offsets[k], ch, limit);
      if (ch.too_many_synthetic) return;
      if (settings.progress && c == 0 && (k & 0x3FFF) == 0) {
        std::uint64_t d = t.offsets[k] - t.offsets[ch.first_streamline];
        settings.progress("voxelising", double(d) / double(std::max<std::uint64_t>(1, chunk_points)));
      }
    }
    ch.first_voxline.push_back(ch.voxlines.size());
  });
  for (const Chunk& ch : chunks)
    if (ch.too_many_synthetic)
      detail::fail_too_many_synthetic(path, s, longest_step2);
  parallel_for_chunks(chunks.size(), threads, [&](std::size_t c) {
    Chunk& ch = chunks[c];
    ch.vertices_per_voxel.assign(ch.index.coords().size(), 0);
    ch.segments_per_voxel.assign(ch.index.coords().size(), 0);
    for (std::uint64_t k = 0; k + 1 < ch.first_voxline.size(); ++k) {
      for (std::uint64_t j = ch.first_voxline[k]; j < ch.first_voxline[k + 1]; ++j) {
        const TempVoxline& v = ch.voxlines[j];
        std::uint64_t own = v.own();
        if (own > kVoxlineCountMask)
          detail::fail_long_voxline(path);
        std::uint64_t used = own + (j + 1 < ch.first_voxline[k + 1] ? 1 : 0);  // + the connecting vertex
        ch.vertices_per_voxel[v.voxel] += used;
        ch.segments_per_voxel[v.voxel] += used - 1;
      }
    }
  });
  if (settings.progress) settings.progress("voxelising", 1.0);

  // Global voxel table, sorted by (z, y, x).
  std::vector<Coord> all;
  for (const Chunk& ch : chunks) all.insert(all.end(), ch.index.coords().begin(), ch.index.coords().end());
  std::sort(all.begin(), all.end(), zyx_less);
  all.erase(std::unique(all.begin(), all.end()), all.end());
  detail::check_voxel_total(all.size(), s, path);
  const std::size_t n_voxels = all.size();
  std::vector<std::uint64_t> voxel_vertices(n_voxels, 0), voxel_segments(n_voxels, 0);
  std::uint64_t n_voxlines = 0, n_synthetic = 0;
  for (Chunk& ch : chunks) {
    const auto& coords = ch.index.coords();
    ch.global_id.resize(coords.size());
    for (std::size_t i = 0; i < coords.size(); ++i) {
      ch.global_id[i] = static_cast<std::uint32_t>(std::lower_bound(all.begin(), all.end(), coords[i], zyx_less) - all.begin());
      voxel_vertices[ch.global_id[i]] += ch.vertices_per_voxel[i];
      voxel_segments[ch.global_id[i]] += ch.segments_per_voxel[i];
    }
    ch.voxline_base = n_voxlines;
    n_voxlines += ch.voxlines.size();
    n_synthetic += ch.synthetic_xyz.size() / 3;
  }

  plan.voxels_.resize(n_voxels);
  std::uint64_t n_vertices = 0, n_segments = 0;
  for (std::size_t i = 0; i < n_voxels; ++i) {
    if (voxel_vertices[i] > std::numeric_limits<std::uint32_t>::max())
      detail::fail_full_voxel(path, s);
    VoxelEntry& v = plan.voxels_[i];
    v = {};
    v.coord[0] = all[i].x;
    v.coord[1] = all[i].y;
    v.coord[2] = all[i].z;
    v.vertex_first = n_vertices;
    v.vertex_count = static_cast<std::uint32_t>(voxel_vertices[i]);
    v.segment_count = static_cast<std::uint32_t>(voxel_segments[i]);
    n_vertices += voxel_vertices[i];
    n_segments += voxel_segments[i];
  }
  // Each chunk writes after the chunks before it inside every block: streamline order is kept.
  {
    std::vector<std::uint64_t> next(n_voxels);
    for (std::size_t i = 0; i < n_voxels; ++i) next[i] = plan.voxels_[i].vertex_first;
    for (Chunk& ch : chunks) {
      ch.cursor.resize(ch.global_id.size());
      for (std::size_t i = 0; i < ch.global_id.size(); ++i) {
        ch.cursor[i] = next[ch.global_id[i]];
        next[ch.global_id[i]] += ch.vertices_per_voxel[i];
      }
    }
  }

  m.vertex_count = n_vertices;
  m.segment_count = n_segments;
  m.voxline_count = n_voxlines;
  m.synthetic_point_count = n_synthetic;
  m.voxel_count = static_cast<std::uint32_t>(n_voxels);
  return plan;
}

VoxlineEnds place_vertices(VoxelPlan&& plan, Tractogram&& t, const VoxelBlocks& out) {
  const MetaSection& m = plan.meta_;
  const unsigned threads = plan.work_->threads;
  std::vector<Chunk>& chunks = plan.work_->chunks;
  const float* pts = t.positions.data();
  if (out.voxels.size() != m.voxel_count || out.vertices.size() != 3 * m.vertex_count ||
      out.voxlines.size() != m.voxline_count || out.streamline_first_voxline.size() != m.streamline_count + 1)
    throw std::logic_error("place_vertices: the output spans do not have the sizes of the plan");
  VoxlineEnds ends(m.vertex_count);
  std::copy(plan.voxels_.begin(), plan.voxels_.end(), out.voxels.begin());

  if (out.vertex_values.size() != t.point_values.size())
    throw std::logic_error("place_vertices: one vertex value array per point value set expected");
  for (std::size_t k = 0; k < out.vertex_values.size(); ++k)
    if (out.vertex_values[k].size() != m.vertex_count || t.point_values[k].values.size() != m.point_count)
      throw std::logic_error("place_vertices: value arrays do not have the sizes of the plan");

  // Pass 2: place vertices, fill the voxline and streamline tables.
  parallel_for_chunks(chunks.size(), threads, [&](std::size_t c) {
    Chunk& ch = chunks[c];
    for (std::uint64_t k = 0; k + 1 < ch.first_voxline.size(); ++k) {
      out.streamline_first_voxline[ch.first_streamline + k] = ch.voxline_base + ch.first_voxline[k];
      const std::uint64_t end = ch.first_voxline[k + 1];
      for (std::uint64_t j = ch.first_voxline[k]; j < end; ++j) {
        const TempVoxline& v = ch.voxlines[j];
        std::uint64_t& cursor = ch.cursor[v.voxel];
        float* dst = out.vertices.data() + 3 * cursor;
        std::uint32_t own = v.own();
        if (v.synthetic != kNoSynthetic) {
          std::memcpy(dst, ch.synthetic_xyz.data() + 3 * v.synthetic, 12);
          dst += 3;
        }
        std::memcpy(dst, pts + 3 * v.src_first, 12ull * v.src_count);
        dst += 3 * v.src_count;
        bool connected = j + 1 < end;
        if (connected) {
          const TempVoxline& w = ch.voxlines[j + 1];
          const float* first = w.synthetic != kNoSynthetic ? ch.synthetic_xyz.data() + 3 * w.synthetic : pts + 3 * w.src_first;
          std::memcpy(dst, first, 12);
        }
        // Values travel with their points: a synthetic point's is interpolated where it lies on its step
        // (from source point src_first - 1 to src_first), a connecting vertex copies the next voxline's first.
        for (std::size_t k = 0; k < out.vertex_values.size(); ++k) {
          const float* src = t.point_values[k].values.data();
          auto first_value = [&](const TempVoxline& x) {
            if (x.synthetic == kNoSynthetic) return src[x.src_first];
            const double a = src[x.src_first - 1], b = src[x.src_first], at = ch.synthetic_t[x.synthetic];
            return static_cast<float>(a + at * (b - a));
          };
          float* dv = out.vertex_values[k].data() + cursor;
          if (v.synthetic != kNoSynthetic) *dv++ = first_value(v);
          std::copy(src + v.src_first, src + v.src_first + v.src_count, dv);
          if (connected) dv[v.src_count] = first_value(ch.voxlines[j + 1]);
        }
        std::uint64_t used = own + (connected ? 1 : 0);
        ends.set(cursor + used - 1);
        cursor += used;
        out.voxlines[ch.voxline_base + j] = {ch.global_id[v.voxel], own | (v.synthetic != kNoSynthetic ? kVoxlineSyntheticFirst : 0u)};
      }
    }
  });
  if (chunks.empty()) std::fill(out.streamline_first_voxline.begin(), out.streamline_first_voxline.end(), 0);
  out.streamline_first_voxline[m.streamline_count] = m.voxline_count;
  plan.work_.reset();
  t.positions.clear();  // the blocks now hold every point: release the source copy before orders are built
  t.positions.shrink_to_fit();
  t.point_values.clear();  // likewise their values
  t.point_values.shrink_to_fit();

  // Tight bounds per voxel.
  parallel_for_chunks(out.voxels.size(), threads, [&](std::size_t i) {
    VoxelEntry& v = out.voxels[i];
    const float* p = out.vertices.data() + 3 * v.vertex_first;
    for (int c = 0; c < 3; ++c) v.tight_min[c] = v.tight_max[c] = p[c];
    for (std::uint64_t k = 1; k < v.vertex_count; ++k)
      for (int c = 0; c < 3; ++c) {
        v.tight_min[c] = std::min(v.tight_min[c], p[3 * k + c]);
        v.tight_max[c] = std::max(v.tight_max[c], p[3 * k + c]);
      }
  });
  return ends;
}

VoxelizedTractogram voxelize(Tractogram&& t, const VoxelizeSettings& settings) {
  t.point_values.clear();  // the in-memory result has no value arrays
  VoxelPlan plan = plan_voxels(t, settings);
  VoxelizedTractogram out;
  out.meta = plan.meta();
  out.voxels.resize(out.meta.voxel_count);
  out.vertices.resize(3 * out.meta.vertex_count);
  out.voxlines.resize(out.meta.voxline_count);
  out.streamline_first_voxline.resize(out.meta.streamline_count + 1);
  out.voxline_ends = place_vertices(std::move(plan), std::move(t),
                                    {out.voxels, out.vertices, out.voxlines, out.streamline_first_voxline, {}});
  return out;
}

}  // namespace vxl
