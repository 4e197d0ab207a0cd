#include "converter/convert/voxelize.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "converter/convert/voxel_table.h"
#include "format/base/parallel.h"
#include "format/vxl_positions.h"

namespace vxl {

namespace {

using detail::kNoSynthetic;
using detail::TempVoxline;
using detail::VoxelIndex;

// One thread's contiguous range of streamlines and its voxlines.
struct StreamlineRange {
  std::uint64_t first_streamline = 0, end_streamline = 0;
  VoxelIndex index;
  std::vector<TempVoxline> voxlines;
  std::vector<std::uint64_t> first_voxline;  // per streamline of the range, range-local
  std::vector<float> synthetic_xyz;
  std::vector<double> synthetic_t;  // per synthetic point: where it lies on its step, for value interpolation
  detail::VoxelUse use;             // by local id
  detail::VoxelBounds bounds;       // by local id, when packing
  detail::LocalVoxels table;        // global ids and cursors, by local id
  std::uint64_t voxline_base = 0;   // first global voxline of this range
  bool too_many_synthetic = false;

  std::span<const TempVoxline> streamline(std::uint64_t k) const {
    return std::span<const TempVoxline>(voxlines).subspan(first_voxline[k], first_voxline[k + 1] - first_voxline[k]);
  }
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

// The voxels' tight bounds, from every range's (the same as set_tight_bounds finds over the placed blocks:
// the bounds cover exactly the vertices place_voxline writes), and a packer for each voxel.
void set_packers(std::span<VoxelEntry> voxels, std::vector<StreamlineRange>& ranges,
                 std::vector<VertexPacker>& packers) {
  detail::VoxelBounds bounds;
  bounds.grow_to(voxels.size());
  for (StreamlineRange& r : ranges) {
    for (std::uint32_t local = 0; local < r.table.global_id.size(); ++local)
      bounds.merge(r.table.global_id[local], r.bounds, local);
    r.bounds = detail::VoxelBounds();
  }
  packers.reserve(voxels.size());
  for (std::uint32_t g = 0; g < voxels.size(); ++g) {
    bounds.set_tight_bounds(g, voxels[g]);
    packers.emplace_back(voxels[g]);
  }
}

// Places voxline j of `streamline` packed: its vertices as place_voxline gives them, quantised by the voxel's
// packer into `words` (the last with its voxline-end bit). Returns the number of vertices.
std::uint64_t place_packed(std::span<const TempVoxline> streamline, std::size_t j, const float* pts,
                           const StreamlineRange& r, const VertexPacker& packer, std::vector<float>& voxline_xyz,
                           std::uint32_t* words) {
  voxline_xyz.resize(3 * (streamline[j].own() + 1));
  const std::uint64_t used = detail::place_voxline(streamline, j, pts, r.synthetic_xyz.data(), voxline_xyz.data());
  packer.words(voxline_xyz.data(), used, words);
  words[used - 1] |= kPackedVoxlineEnd;
  return used;
}

}  // namespace

struct VoxelPlan::Work {
  unsigned threads = 1;
  std::uint32_t levels = 1;
  std::vector<StreamlineRange> ranges;
  bool pack_positions = false;
  std::vector<VertexPacker> packers;  // by voxel, when packing
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
  const std::uint32_t levels = settings.levels;
  detail::check_level_count(levels, path);
  const std::uint64_t n_streamlines = t.streamline_count(), n_points = t.point_count();
  const float* pts = t.positions.data();

  VoxelPlan plan;
  plan.work_->threads = threads;
  plan.work_->levels = levels;
  plan.work_->pack_positions = settings.pack_positions;
  MetaSection& m = plan.meta_;
  m.streamline_count = n_streamlines;
  m.point_count = n_points;
  m.voxel_size = s;

  // The same streamline ranges serve the bounds scan and pass 1.
  const std::vector<std::uint64_t> bounds = split_by_points(t.offsets, threads);
  std::vector<detail::BoundsScan> parts(bounds.size() - 1);
  plan.lengths_.resize(n_streamlines);
  parallel_for(parts.size(), threads, [&](std::uint64_t c, unsigned) {
    parts[c].add(pts, t.offsets.data(), bounds[c], bounds[c + 1], 0, plan.lengths_.data());
  });
  detail::BoundsScan scan;
  for (const detail::BoundsScan& part : parts) scan.merge(part);  // in streamline order: the first bad point wins
  scan.check(path);
  if (n_points == 0) return plan;  // no voxels; place_vertices fills STRM with zeros
  const double lo[3] = {scan.lo[0], scan.lo[1], scan.lo[2]}, hi[3] = {scan.hi[0], scan.hi[1], scan.hi[2]};
  const detail::Grid grid = detail::set_grid(m, lo, hi, path);

  // Pass 1: voxlines per range of streamlines, then each range's vertex and segment count per voxel.
  std::vector<StreamlineRange>& ranges = plan.work_->ranges;
  ranges.resize(bounds.size() - 1);
  parallel_for(ranges.size(), threads, [&](std::uint64_t c, unsigned) {
    StreamlineRange& r = ranges[c];
    r.first_streamline = bounds[c];
    r.end_streamline = bounds[c + 1];
    std::uint64_t range_points = t.offsets[r.end_streamline] - t.offsets[r.first_streamline];
    r.voxlines.reserve(range_points / 4 + 16);
    r.first_voxline.reserve(r.end_streamline - r.first_streamline + 1);
    std::uint64_t limit = static_cast<std::uint64_t>(settings.max_synthetic_per_point * double(range_points)) + 4096;
    for (std::uint64_t k = r.first_streamline; k < r.end_streamline; ++k) {
      r.first_voxline.push_back(r.voxlines.size());
      detail::voxelize_streamline(grid, pts, t.offsets[k], t.offsets[k + 1] - t.offsets[k], r, limit);
      if (r.too_many_synthetic) return;
      if (settings.progress && c == 0 && (k & 0x3FFF) == 0) {
        std::uint64_t d = t.offsets[k] - t.offsets[r.first_streamline];
        settings.progress("voxelising", double(d) / double(std::max<std::uint64_t>(1, range_points)));
      }
    }
    r.first_voxline.push_back(r.voxlines.size());
  });
  for (const StreamlineRange& r : ranges)
    if (r.too_many_synthetic) detail::fail_too_many_synthetic(path, s, scan.longest_step2);
  parallel_for(ranges.size(), threads, [&](std::uint64_t c, unsigned) {
    StreamlineRange& r = ranges[c];
    r.use = detail::VoxelUse(levels);
    r.use.grow_to(r.index.coords().size());
    if (settings.pack_positions) r.bounds.grow_to(r.index.coords().size());
    for (std::uint64_t k = 0; k + 1 < r.first_voxline.size(); ++k) {
      detail::count_voxel_use(r.streamline(k), streamline_depth(r.first_streamline + k, levels), r.use, path);
      if (settings.pack_positions)
        for (std::size_t j = 0; j < r.streamline(k).size(); ++j)
          r.bounds.add_voxline(r.streamline(k), j, pts, r.synthetic_xyz.data());
    }
  });
  if (settings.progress) settings.progress("voxelising", 1.0);

  // Global voxel table, sorted by (z, y, x).
  std::vector<detail::LocalVoxels> tables;
  for (StreamlineRange& r : ranges) tables.push_back({&r.index.coords(), &r.use, {}, {}});
  detail::VoxelTable table = detail::build_voxel_table(tables, levels, m, path);
  plan.voxels_ = std::move(table.voxels);
  plan.levels_ = std::move(table.levels);
  std::uint64_t n_voxlines = 0, n_synthetic = 0;
  for (std::size_t c = 0; c < ranges.size(); ++c) {
    StreamlineRange& r = ranges[c];
    r.table = std::move(tables[c]);
    r.table.use = nullptr;
    r.use = detail::VoxelUse(levels);
    r.voxline_base = n_voxlines;
    n_voxlines += r.voxlines.size();
    n_synthetic += r.synthetic_xyz.size() / 3;
  }
  m.voxline_count = n_voxlines;
  m.synthetic_point_count = n_synthetic;
  if (settings.pack_positions) set_packers(plan.voxels_, ranges, plan.work_->packers);
  return plan;
}

VoxlineEnds place_vertices(VoxelPlan&& plan, Tractogram&& t, const VoxelBlocks& out) {
  const MetaSection& m = plan.meta_;
  const unsigned threads = plan.work_->threads;
  const std::uint32_t levels = plan.work_->levels;
  std::vector<StreamlineRange>& ranges = plan.work_->ranges;
  const float* pts = t.positions.data();
  const bool packing = plan.work_->pack_positions;
  if (out.voxels.size() != m.voxel_count ||
      (packing ? out.packed_vertices.size() != m.vertex_count : out.vertices.size() != 3 * m.vertex_count) ||
      out.voxlines.size() != m.voxline_count || out.streamline_first_voxline.size() != m.streamline_count + 1 ||
      out.levels.size() != plan.levels_.size())
    throw std::logic_error("place_vertices: the output spans do not have the sizes of the plan");
  VoxlineEnds ends(m.vertex_count);
  std::copy(plan.voxels_.begin(), plan.voxels_.end(), out.voxels.begin());
  std::copy(plan.levels_.begin(), plan.levels_.end(), out.levels.begin());

  if (out.vertex_values.size() != t.point_values.size())
    throw std::logic_error("place_vertices: one vertex value array per point value set expected");
  for (std::size_t k = 0; k < out.vertex_values.size(); ++k)
    if (out.vertex_values[k].size() != m.vertex_count || t.point_values[k].values.size() != m.point_count)
      throw std::logic_error("place_vertices: value arrays do not have the sizes of the plan");

  // Pass 2: place vertices, fill the voxline and streamline tables.
  const std::vector<VertexPacker>& packers = plan.work_->packers;
  parallel_for(ranges.size(), threads, [&](std::uint64_t c, unsigned) {
    StreamlineRange& r = ranges[c];
    std::vector<float> voxline_xyz;  // one voxline's vertices on their way to being packed
    for (std::uint64_t k = 0; k + 1 < r.first_voxline.size(); ++k) {
      out.streamline_first_voxline[r.first_streamline + k] = r.voxline_base + r.first_voxline[k];
      const std::span<const TempVoxline> streamline = r.streamline(k);
      const std::uint32_t depth = streamline_depth(r.first_streamline + k, levels);
      for (std::size_t j = 0; j < streamline.size(); ++j) {
        const TempVoxline& v = streamline[j];
        std::uint64_t& cursor = r.table.cursor[std::size_t(v.voxel) * levels + depth];
        const std::uint64_t used = packing ? place_packed(streamline, j, pts, r, packers[r.table.global_id[v.voxel]],
                                                          voxline_xyz, out.packed_vertices.data() + cursor)
                                           : detail::place_voxline(streamline, j, pts, r.synthetic_xyz.data(),
                                                                   out.vertices.data() + 3 * cursor);
        // Values travel with their points: a synthetic point's is interpolated where it lies on its step
        // (from source point src_first - 1 to src_first), a connecting vertex copies the next voxline's first.
        const bool connected = j + 1 < streamline.size();
        for (std::size_t s = 0; s < out.vertex_values.size(); ++s) {
          const float* src = t.point_values[s].values.data();
          auto first_value = [&](const TempVoxline& x) {
            if (x.synthetic == kNoSynthetic) return src[x.src_first];
            const double a = src[x.src_first - 1], b = src[x.src_first], at = r.synthetic_t[x.synthetic];
            return static_cast<float>(a + at * (b - a));
          };
          float* dv = out.vertex_values[s].data() + cursor;
          if (v.synthetic != kNoSynthetic) *dv++ = first_value(v);
          std::copy(src + v.src_first, src + v.src_first + v.src_count, dv);
          if (connected) dv[v.src_count] = first_value(streamline[j + 1]);
        }
        ends.set(cursor + used - 1);
        cursor += used;
        out.voxlines[r.voxline_base + r.first_voxline[k] + j] = {
            r.table.global_id[v.voxel], v.own() | (v.synthetic != kNoSynthetic ? kVoxlineSyntheticFirst : 0u)};
      }
    }
  });
  if (ranges.empty()) std::fill(out.streamline_first_voxline.begin(), out.streamline_first_voxline.end(), 0);
  out.streamline_first_voxline[m.streamline_count] = m.voxline_count;
  plan.work_.reset();
  t.positions.clear();  // the blocks now hold every point: release the source copy before orders are built
  t.positions.shrink_to_fit();
  t.point_values.clear();  // likewise their values
  t.point_values.shrink_to_fit();

  if (packing) return ends;  // the tight bounds are set, every vertex packed
  // Tight bounds per voxel, in pieces of 4096 voxels.
  constexpr std::size_t kPiece = 4096;
  parallel_for((out.voxels.size() + kPiece - 1) / kPiece, threads, [&](std::uint64_t p, unsigned) {
    detail::set_tight_bounds(out.voxels.subspan(p * kPiece, std::min(kPiece, out.voxels.size() - p * kPiece)),
                             out.vertices.data(), 0);
  });
  return ends;
}

VoxelizedTractogram voxelize(Tractogram&& t, const VoxelizeSettings& settings) {
  t.point_values.clear();  // the in-memory result has no value arrays
  VoxelPlan plan = plan_voxels(t, settings);
  VoxelizedTractogram out;
  out.meta = plan.meta();
  out.voxels.resize(out.meta.voxel_count);
  out.levels.resize(plan.levels().size());
  out.vertices.resize(3 * out.meta.vertex_count);
  out.voxlines.resize(out.meta.voxline_count);
  out.streamline_first_voxline.resize(out.meta.streamline_count + 1);
  out.voxline_ends =
      place_vertices(std::move(plan), std::move(t),
                     {out.voxels, out.levels, out.vertices, out.voxlines, out.streamline_first_voxline, {}, {}});
  return out;
}

}  // namespace vxl
