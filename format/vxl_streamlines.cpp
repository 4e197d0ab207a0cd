#include "format/vxl_streamlines.h"

#include <cmath>
#include <cstring>
#include <vector>

#include "format/base/error.h"

namespace vxl {

void walk_streamlines(const VxlFile& f, const WalkCallbacks& cb) {
  const std::string& p = f.path();
  const MetaSection& m = f.meta();
  auto voxels = f.voxels();
  auto voxlines = f.voxlines();
  auto strm = f.streamline_first_voxline();
  const bool packed = f.position_encoding() == PositionEncoding::Packed;
  const std::uint64_t vxln_at = f.find_section(section_id("VXLN"))->offset;

  f.check_streamline_table();

  // One cursor per voxel and depth: a voxel's block holds the voxlines of deeper streamlines first (spec
  // §5.4, §5.12), each depth's in streamline order.
  const std::uint32_t levels = f.level_count();
  // Each cursor's end is kept beside it: a walk that reads few streamlines costs these lookups per voxline.
  std::vector<std::uint64_t> cursor(voxels.size() * levels), cursor_end(voxels.size() * levels);
  for (std::size_t i = 0; i < voxels.size(); ++i)
    for (std::uint32_t d = 0; d < levels; ++d) {
      cursor[i * levels + d] = voxels[i].vertex_first + depth_first_vertex(f.levels_of(i), d);
      cursor_end[i * levels + d] = voxels[i].vertex_first + depth_end_vertex(voxels[i], f.levels_of(i), d);
    }
  std::vector<float> points;
  std::uint64_t total_points = 0, synthetic = 0;
  // The mapped pages read are let go every so often: a walk through a whole file (export, a large selection)
  // otherwise keeps every page it touched resident (the 1M set's blocks and tables: 365 MB).
  constexpr std::uint64_t kReleaseEvery = 64ull << 20;
  const std::uint64_t vertex_bytes = packed ? 4 : 12;
  std::uint64_t read_since_release = 0;
  // A connecting vertex and the next voxline's first point are one source point, stored in two voxels'
  // blocks: equal bit for bit as float32, within both voxels' error bounds when packed (spec §5.4).
  std::vector<double> error_bound;  // per voxel, packed
  if (packed)
    for (const VoxelEntry& v : voxels) error_bound.push_back(packed_error_bound(v));
  auto same_point = [&](const float* a, std::uint32_t voxel_a, const float* b, std::uint32_t voxel_b) {
    if (!packed) return std::memcmp(a, b, 12) == 0;
    const double tolerance = error_bound[voxel_a] + error_bound[voxel_b];
    for (int c = 0; c < 3; ++c)
      if (!(std::abs(double(a[c]) - double(b[c])) <= tolerance)) return false;
    return true;
  };

  for (std::uint64_t s = 0; s < m.streamline_count; ++s) {
    const std::uint64_t first = strm[s], last = strm[s + 1];
    const std::uint32_t depth = streamline_depth(s, levels);
    const bool read = !cb.read_points || cb.read_points(s);
    points.clear();
    float pending_connector[3];  // previous voxline's connecting vertex, when `connector_voxel` is set
    std::int64_t connector_voxel = -1;
    for (std::uint64_t j = first; j < last; ++j) {
      const VoxlineEntry& e = voxlines[j];
      const std::uint64_t at = vxln_at + 8 * j;
      f.check_voxline(j);
      const std::uint32_t own = e.count_flags & kVoxlineCountMask;
      const bool synthetic_first = (e.count_flags & kVoxlineSyntheticFirst) != 0;
      const bool connected = j + 1 < last;
      if (synthetic_first && j == first) fail_input(p, at, "a streamline cannot start with a synthetic point");
      std::uint64_t& here = cursor[e.voxel * levels + depth];
      const std::uint64_t end = cursor_end[e.voxel * levels + depth];
      const std::uint64_t need = std::uint64_t(own) + (connected ? 1 : 0);
      if (here > end || need > end - here)
        fail_input(p, at, "voxline runs past its voxel's vertex block (or its level's part of it)");
      const std::uint32_t skip = synthetic_first ? 1 : 0;
      synthetic += skip;
      total_points += own - skip;
      read_since_release += sizeof(VoxlineEntry);
      if (read) {
        read_since_release += need * vertex_bytes;
        // Decoded straight into `points`; the synthetic first point and the connecting vertex are taken off after.
        const std::size_t start = points.size();
        points.resize(start + 3 * need);
        float* const block = points.data() + start;
        f.read_vertices(e.voxel, here, need, block);
        if (connector_voxel >= 0 &&
            !same_point(pending_connector, static_cast<std::uint32_t>(connector_voxel), block, e.voxel))
          fail_input(p, at, "connecting vertex differs from the next voxline's first point");
        connector_voxel = connected ? std::int64_t(e.voxel) : -1;
        if (connected) std::copy_n(block + 3 * own, 3, pending_connector);
        if (skip > 0) std::copy(block + 3 * skip, block + 3 * own, block);
        points.resize(start + 3 * (own - skip));
      }
      if (cb.voxline) cb.voxline({s, e.voxel, here, own, synthetic_first, j == first, connected});
      here += need;
    }
    if (read && cb.streamline) cb.streamline(s, points);
    if (read_since_release > kReleaseEvery) {
      f.release_resident_pages();
      read_since_release = 0;
    }
  }
  for (std::size_t i = 0; i < voxels.size(); ++i)
    for (std::uint32_t d = 0; d < levels; ++d)
      if (cursor[i * levels + d] != cursor_end[i * levels + d])
        fail_input(p, f.find_section(section_id("VOXT"))->offset + 64 * i,
                   "voxel block has vertices no voxline uses" +
                       (levels > 1 ? " (at depth " + std::to_string(d) + ")" : std::string()));
  if (total_points != m.point_count)
    fail_input(
        p, std::nullopt,
        "streamlines hold " + std::to_string(total_points) + " points but META says " + std::to_string(m.point_count));
  if (synthetic != m.synthetic_point_count) fail_input(p, std::nullopt, "synthetic point count does not match META");
}

}  // namespace vxl
