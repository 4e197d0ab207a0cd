#include "converter/selection/streamline_selection.h"

#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "format/error.h"
#include "format/json_limits.h"
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

// Per voxel, the regions that may touch its bounds (decoded packed positions may stray from the tight
// bounds by the file's error bound, so the box is widened by it).
std::vector<Bits> regions_per_voxel(const VxlFile& file, const RegionTable& table, std::uint32_t& touched) {
  const auto voxels = file.voxels();
  const bool packed = file.position_encoding() == PositionEncoding::Packed;
  std::vector<Bits> out(voxels.size(), 0);
  touched = 0;
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    const VoxelEntry& v = voxels[i];
    float lo[3], hi[3];
    const float widen = packed ? static_cast<float>(packed_error_bound(v)) : 0.0f;
    for (int c = 0; c < 3; ++c) lo[c] = v.tight_min[c] - widen, hi[c] = v.tight_max[c] + widen;
    for (std::size_t r = 0; r < table.regions.size(); ++r)
      if (table.regions[r]->may_touch(lo, hi)) out[i] |= Bits(1) << r;
    touched += out[i] != 0;
  }
  return out;
}

double polyline_length(std::span<const float> xyz) {
  double length = 0;
  for (std::size_t i = 3; i + 2 < xyz.size(); i += 3) {
    const double dx = double(xyz[i]) - xyz[i - 3], dy = double(xyz[i + 1]) - xyz[i - 2],
                 dz = double(xyz[i + 2]) - xyz[i - 1];
    length += std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  return length;
}

// A number from the source header kept in PROV (a TCK's "key: value" lines are arrays of strings there).
std::optional<double> source_header_number(const VxlFile& file, const char* key) {
  const nlohmann::json prov = parse_json(file.provenance_json(), file.path(), file.provenance_offset(), "PROV");
  if (!prov.is_object() || !prov.contains("source") || !prov["source"].is_object()) return std::nullopt;
  const nlohmann::json header = prov["source"].value("header", nlohmann::json());
  if (!header.is_object() || !header.contains(key)) return std::nullopt;
  nlohmann::json v = header[key];
  if (v.is_array() && !v.empty()) v = v.back();
  try {
    const double x = v.is_number() ? v.get<double>() : v.is_string() ? std::stod(v.get<std::string>()) : NAN;
    return std::isfinite(x) ? std::optional<double>(x) : std::nullopt;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace

double length_limit_margin(const VxlFile& file) {
  const std::optional<double> step = source_header_number(file, "step_size");
  if (!step || *step <= 0) return 0;
  const std::optional<double> downsample = source_header_number(file, "downsample_factor");
  return (downsample && *downsample > 0 ? 0.5 / *downsample : 0.1) * *step;
}

SelectionResult select_streamlines(const VxlFile& file, const SelectionCriteria& criteria) {
  if (criteria.min_length && criteria.max_length && *criteria.min_length > *criteria.max_length)
    throw Error(ErrorKind::Usage, "--min-length", std::nullopt, "the minimum length is above the maximum length");
  const RegionTable table(criteria);
  SelectionResult result;
  const std::uint64_t n = file.meta().streamline_count;
  const std::vector<Bits> voxel_regions = regions_per_voxel(file, table, result.voxels_touched);
  const Bits needed = table.include | table.ends;

  // Pass over the voxline table: each streamline's regions hit, from the voxlines in touched voxels only.
  // A voxline's vertices are found by its voxel's cursor (spec §5.6), so cursors are kept for the touched
  // voxels alone and a voxline elsewhere costs one table entry and one look at its voxel's bits: this loop
  // is the query's cost for a small region, and it is written out rather than run through walk_streamlines'
  // callbacks for that reason (with the cursor ends below, the empty query on the 1M set went from 0.3 s to 0.12 s).
  const auto strm = file.streamline_first_voxline();
  const auto voxlines = file.voxlines();
  const auto voxels = file.voxels();
  const std::uint32_t levels = file.level_count();
  const std::uint64_t strm_at = file.find_section(section_id("STRM"))->offset;
  const std::uint64_t vxln_at = file.find_section(section_id("VXLN"))->offset;
  std::vector<std::uint64_t> cursor(voxels.size() * levels, 0);
  for (std::size_t i = 0; i < voxels.size(); ++i)
    if (voxel_regions[i] != 0)
      for (std::uint32_t d = 0; d < levels; ++d)
        cursor[i * levels + d] = voxels[i].vertex_first + depth_first_vertex(file.levels_of(i), d);
  std::vector<std::uint8_t> passes(n, 0);
  result.streamlines_per_region.assign(table.regions.size(), 0);
  std::vector<float> xyz;
  if (strm[0] != 0) fail_input(file.path(), strm_at, "streamline table must start at voxline 0");
  for (std::uint64_t s = 0; s < n; ++s) {
    const std::uint64_t first = strm[s], last = strm[s + 1];
    if (last < first || last > voxlines.size())
      fail_input(file.path(), strm_at + 8 * (s + 1), "streamline table not non-decreasing");
    Bits hit = 0;
    std::uint32_t depth = 0;
    bool depth_known = false;
    for (std::uint64_t j = first; j < last; ++j) {
      const VoxlineEntry& e = voxlines[j];
      if (e.voxel >= voxels.size())
        fail_input(file.path(), vxln_at + 8 * j, "voxline refers to a voxel past the table");
      const Bits touching = voxel_regions[e.voxel];
      if (touching == 0) continue;
      if (!depth_known) depth = streamline_depth(s, levels), depth_known = true;
      const std::uint32_t own = e.count_flags & kVoxlineCountMask;
      const bool connected = j + 1 < last, first_of_streamline = j == first;
      if (own == 0) fail_input(file.path(), vxln_at + 8 * j, "voxline with no points");
      std::uint64_t& here = cursor[std::size_t(e.voxel) * levels + depth];
      const std::uint64_t end =
          voxels[e.voxel].vertex_first + depth_end_vertex(voxels[e.voxel], file.levels_of(e.voxel), depth);
      const std::uint64_t need = std::uint64_t(own) + (connected ? 1 : 0);
      if (here > end || need > end - here)
        fail_input(file.path(), vxln_at + 8 * j,
                   "voxline runs past its voxel's vertex block (or its level's part of it)");
      const std::uint64_t first_vertex = here;
      here += need;
      const Bits wanted = touching & ~hit;
      const Bits anywhere = wanted & (table.include | table.exclude);
      const Bits at_ends = (first_of_streamline || !connected) ? wanted & table.ends : 0;
      if ((anywhere | at_ends) == 0) continue;
      xyz.resize(3 * std::size_t(own));
      file.read_vertices(e.voxel, first_vertex, own, xyz.data());
      const std::uint32_t from = (e.count_flags & kVoxlineSyntheticFirst) ? 1 : 0;
      result.points_tested += own - from;
      for (std::uint32_t i = from; i < own; ++i) {
        const float* p = &xyz[3 * std::size_t(i)];
        Bits test = anywhere & ~hit;
        if ((i == 0 && first_of_streamline) || (i + 1 == own && !connected)) test |= at_ends & ~hit;
        for (Bits b = test; b != 0; b &= b - 1) {
          const int r = std::countr_zero(b);
          if (table.regions[r]->contains(p)) hit |= Bits(1) << r;
        }
      }
    }
    passes[s] = (hit & needed) == needed && (hit & table.exclude) == 0;
    for (Bits b = hit; b != 0; b &= b - 1) ++result.streamlines_per_region[std::countr_zero(b)];
  }
  const std::uint64_t vertex_bytes = file.position_encoding() == PositionEncoding::Packed ? 4 : 12;
  result.bytes_read = file.voxels().size_bytes() + file.streamline_first_voxline().size_bytes() +
                      file.voxlines().size_bytes() + result.points_tested * vertex_bytes;

  // Length limits: the points of the streamlines still in.
  if (criteria.min_length || criteria.max_length) {
    const double margin = length_limit_margin(file);
    WalkCallbacks lengths;
    lengths.read_points = [&](std::uint64_t s) { return passes[s] != 0; };
    lengths.streamline = [&](std::uint64_t s, std::span<const float> points) {
      ++result.streamlines_measured;
      result.bytes_read += points.size() / 3 * vertex_bytes;
      const double length = polyline_length(points);
      if ((criteria.min_length && length < *criteria.min_length - margin) ||
          (criteria.max_length && length > *criteria.max_length + margin))
        passes[s] = 0;
    };
    walk_streamlines(file, lengths);
  }
  for (std::uint64_t s = 0; s < n; ++s)
    if ((passes[s] != 0) != criteria.invert) result.streamlines.push_back(s);
  return result;
}

}  // namespace vxl
