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

namespace vxl {

unsigned resolve_threads(unsigned requested) {
  if (requested > 0) return requested;
  unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : n;
}

namespace {

constexpr std::uint64_t kNoSynthetic = std::numeric_limits<std::uint64_t>::max();

struct Coord {
  std::int32_t x, y, z;
  bool operator==(const Coord&) const = default;
};
bool zyx_less(const Coord& a, const Coord& b) {
  if (a.z != b.z) return a.z < b.z;
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

// Open-addressing hash map from voxel coordinate to a dense local id. Only consulted when a streamline
// changes voxel (about one point in seven at 10 mm), so simplicity beats cleverness here.
class VoxelIndex {
 public:
  std::uint32_t find_or_insert(const Coord& c) {
    if ((coords_.size() + 1) * 2 > slots_.size()) grow();
    std::size_t mask = slots_.size() - 1;
    for (std::size_t i = hash(c) & mask;; i = (i + 1) & mask) {
      std::uint32_t id = slots_[i];
      if (id == kEmpty) {
        slots_[i] = static_cast<std::uint32_t>(coords_.size());
        coords_.push_back(c);
        return slots_[i];
      }
      if (coords_[id] == c) return id;
    }
  }
  const std::vector<Coord>& coords() const { return coords_; }

 private:
  static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
  static std::size_t hash(const Coord& c) {
    std::uint64_t h = std::uint64_t(std::uint32_t(c.x)) * 0x9E3779B97F4A7C15ull;
    h ^= std::uint64_t(std::uint32_t(c.y)) * 0xC2B2AE3D27D4EB4Full;
    h ^= std::uint64_t(std::uint32_t(c.z)) * 0x165667B19E3779F9ull;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
  void grow() {
    slots_.assign(std::max<std::size_t>(64, slots_.size() * 2), kEmpty);
    std::size_t mask = slots_.size() - 1;
    for (std::uint32_t id = 0; id < coords_.size(); ++id) {
      std::size_t i = hash(coords_[id]) & mask;
      while (slots_[i] != kEmpty) i = (i + 1) & mask;
      slots_[i] = id;
    }
  }
  std::vector<std::uint32_t> slots_;
  std::vector<Coord> coords_;
};

// A voxline before its vertices are placed: an optional synthetic first point, then source points.
struct TempVoxline {
  std::uint32_t voxel;      // chunk-local voxel id
  std::uint32_t src_count;  // source points after the optional synthetic point
  std::uint64_t src_first;  // first source point index
  std::uint64_t synthetic;  // index into Chunk::synthetic_xyz, or kNoSynthetic
  std::uint32_t own() const { return src_count + (synthetic != kNoSynthetic ? 1u : 0u); }
};

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

struct Grid {
  double origin[3];
  double size;
  // voxel_coordinate() (spec §6.1) of a source point. Every point is >= the origin, so the quotient is
  // >= 0 and below the grid size (< 2^31), where truncation is floor: this avoids a floor() library
  // call per coordinate (the baseline x86-64 ISA has no rounding instruction).
  Coord voxel_of(const float* p) const {
    return {static_cast<std::int32_t>((static_cast<double>(p[0]) - origin[0]) / size),
            static_cast<std::int32_t>((static_cast<double>(p[1]) - origin[1]) / size),
            static_cast<std::int32_t>((static_cast<double>(p[2]) - origin[2]) / size)};
  }
};

int chebyshev(const Coord& a, const Coord& b) {
  return std::max({std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(a.z - b.z)});
}

// Appends the voxlines of one streamline (Algorithm 1, with face splitting of long steps: spec §6.3).
void voxelize_streamline(const Grid& grid, const float* pts, std::uint64_t first, std::uint64_t n, Chunk& ch,
                         std::uint64_t synthetic_limit) {
  if (n == 0) return;
  Coord current = grid.voxel_of(pts + 3 * first);
  TempVoxline open{ch.index.find_or_insert(current), 0, first, kNoSynthetic};
  auto close = [&](std::uint64_t end_point) {
    open.src_count = static_cast<std::uint32_t>(end_point - open.src_first);
    ch.voxlines.push_back(open);
  };
  for (std::uint64_t i = first + 1; i < first + n; ++i) {
    Coord next = grid.voxel_of(pts + 3 * i);
    if (next == current) continue;
    if (chebyshev(current, next) <= 1) {
      close(i);
      current = next;
      open = {ch.index.find_or_insert(current), 0, i, kNoSynthetic};
      continue;
    }
    // Long step a -> b: cross the faces in order of the line parameter t.
    const float* a = pts + 3 * (i - 1);
    const float* b = pts + 3 * i;
    struct Crossing {
      double t;
      int axis;
      int step;
    };
    const std::int32_t from[3] = {current.x, current.y, current.z};
    const std::int32_t to[3] = {next.x, next.y, next.z};
    // Check the budget before allocating: one step can cross billions of faces (found by fuzzing).
    std::uint64_t faces = 0;
    for (int c = 0; c < 3; ++c) faces += static_cast<std::uint64_t>(std::abs(std::int64_t(to[c]) - from[c]));
    if (ch.synthetic_xyz.size() / 3 + faces > synthetic_limit) {
      ch.too_many_synthetic = true;
      return;
    }
    std::vector<Crossing> crossings;
    crossings.reserve(faces);
    for (int c = 0; c < 3; ++c) {
      int step = to[c] > from[c] ? 1 : -1;
      double da = static_cast<double>(a[c]), db = static_cast<double>(b[c]);
      for (std::int32_t k = from[c]; k != to[c]; k += step) {
        // the face between voxel k and k + step
        double plane = grid.origin[c] + grid.size * static_cast<double>(step > 0 ? k + 1 : k);
        double t = (plane - da) / (db - da);
        crossings.push_back({std::clamp(t, 0.0, 1.0), c, step});
      }
    }
    std::stable_sort(crossings.begin(), crossings.end(), [](const Crossing& x, const Crossing& y) { return x.t < y.t; });
    std::int32_t at[3] = {from[0], from[1], from[2]};
    for (std::size_t k = 0; k < crossings.size();) {
      double t = crossings[k].t;
      for (; k < crossings.size() && crossings[k].t == t; ++k) at[crossings[k].axis] += crossings[k].step;
      close(i);
      std::uint64_t s = ch.synthetic_xyz.size() / 3;
      for (int c = 0; c < 3; ++c) {
        double da = static_cast<double>(a[c]), db = static_cast<double>(b[c]);
        ch.synthetic_xyz.push_back(static_cast<float>(da + t * (db - da)));
      }
      ch.synthetic_t.push_back(t);
      open = {ch.index.find_or_insert({at[0], at[1], at[2]}), 0, i, s};
    }
    if (ch.synthetic_xyz.size() / 3 > synthetic_limit) {
      ch.too_many_synthetic = true;
      return;
    }
    current = next;
  }
  close(first + n);
}

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
  if (!std::isfinite(s) || !(s > 0)) throw Error(ErrorKind::Usage, path, std::nullopt, "voxel size must be a positive number of mm");
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
      throw Error(ErrorKind::Input, path, std::nullopt,
                  "non-finite coordinate in streamline " + std::to_string(b.bad_streamline) + " (point " +
                      std::to_string(b.bad_point) + ")");
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], double(b.lo[c]));
      hi[c] = std::max(hi[c], double(b.hi[c]));
    }
    longest_step2 = std::max(longest_step2, b.longest_step2);
  }
  if (n_points == 0) return plan;  // no voxels; place_vertices fills STRM with zeros
  Grid grid{{lo[0], lo[1], lo[2]}, s};
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
      throw Error(ErrorKind::Unsupported, path, std::nullopt,
                  "voxel size " + format_mm(s) + " mm is far below the longest step (" + format_mm(std::sqrt(longest_step2)) +
                      " mm): splitting steps at voxel faces would more than double the points; use --voxel-size " +
                      format_mm(std::sqrt(longest_step2)) + " or larger");
  parallel_for_chunks(chunks.size(), threads, [&](std::size_t c) {
    Chunk& ch = chunks[c];
    ch.vertices_per_voxel.assign(ch.index.coords().size(), 0);
    ch.segments_per_voxel.assign(ch.index.coords().size(), 0);
    for (std::uint64_t k = 0; k + 1 < ch.first_voxline.size(); ++k) {
      for (std::uint64_t j = ch.first_voxline[k]; j < ch.first_voxline[k + 1]; ++j) {
        const TempVoxline& v = ch.voxlines[j];
        std::uint64_t own = v.own();
        if (own > kVoxlineCountMask)
          throw Error(ErrorKind::Unsupported, path, std::nullopt, "a voxline of more than 2^31-1 points; use a smaller --voxel-size");
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
  if (all.size() >= std::uint64_t(std::numeric_limits<std::int32_t>::max()))
    throw Error(ErrorKind::Unsupported, path, std::nullopt,
                "more than 2^31 non-empty voxels; use a larger --voxel-size than " + format_mm(s));
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
      throw Error(ErrorKind::Unsupported, path, std::nullopt,
                  "a voxel holds more than 2^32-1 vertices; use a --voxel-size smaller than " + format_mm(s));
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
