#include "converter/package/unpack.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "converter/convert/segment_orders.h"
#include "converter/convert/voxel_table.h"
#include "converter/package/unpack_positions.h"
#include "converter/package/unpack_structure.h"
#include "converter/pipeline/conversion_plan.h"
#include "converter/pipeline/range_orders.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/base/memory_available.h"
#include "format/base/parallel.h"
#include "format/voxel_voxlines.h"
#include "format/vxl_file.h"
#include "format/vxl_group_values.h"
#include "format/vxl_stream_writer.h"
#include "format/vxl_value_sets.h"
#include "format/vxlz_package.h"
#include "format/vxlz_shipping_order.h"
#include "format/vxlz_tables.h"
#include "format/vxlz_values.h"

namespace vxl {
namespace {

// The stagings of VERT's blocks when it is written block by block (write_positions_in_blocks): within a conversion's
// bounds, 128 KiB down to one 4 KiB block, the largest power of two whose stagings open at once take at most a
// sixteenth of the memory allowed (the 1M package in level order within 256 MiB: 16 KiB, 14 MiB open at once). 0 where
// they would take more than a quarter of VERT and more than 16 MiB (many small voxels): holding VERT whole then costs
// little more.
std::uint64_t vertex_block_staging_bytes(const UnpackStructure& s, const PackSection& pack, std::uint64_t vert_bytes,
                                         std::uint64_t memory_allowed) {
  std::uint64_t staging = 128 * 1024;
  while (staging > DirectRegionWriter::kBlock && open_block_staging_bytes(s, pack, staging) > memory_allowed / 16)
    staging /= 2;
  const std::uint64_t open = open_block_staging_bytes(s, pack, staging);
  return open <= std::max<std::uint64_t>(vert_bytes / 4, 16ull << 20) ? staging : 0;
}

// Every voxline takes at least a byte of each of its streams (VXLV, VXLC): META's count is refused when `stream` (the
// inflated section `id`) cannot hold it, before anything is allocated for it.
void check_stream_holds_voxlines(const VxlzFile& f, std::uint32_t id, const std::vector<std::uint8_t>& stream) {
  if (f.meta().voxline_count > stream.size())
    fail_input(f.path(), f.context(id).section_offset,
               "stream too short for META's " + std::to_string(f.meta().voxline_count) + " voxlines");
}

// Inflates and decodes the voxline table, the voxel and the count streams side by side.
std::vector<VoxlineEntry> read_voxlines(const VxlzFile& f, std::span<const std::array<std::int32_t, 3>> coords) {
  const std::uint64_t l = f.meta().voxline_count;
  const std::uint32_t vxlv = section_id("VXLV"), vxlc = section_id("VXLC");
  std::vector<std::uint8_t> voxel_stream, count_stream;
  std::vector<VoxlineEntry> voxlines;
  auto both = [](auto&& voxel_part, auto&& count_part) { parallel_invoke(true, voxel_part, count_part); };
  both([&] { voxel_stream = f.inflate(vxlv); }, [&] { count_stream = f.inflate(vxlc); });
  check_stream_holds_voxlines(f, vxlv, voxel_stream);
  check_stream_holds_voxlines(f, vxlc, count_stream);
  voxlines.resize(l);
  both([&] { decode_voxline_voxels(voxel_stream, coords, voxlines, f.context(vxlv)); },
       [&] { decode_voxline_counts(count_stream, voxlines, f.context(vxlc)); });
  return voxlines;
}

// Keeps the streamlines of depth `min_depth` or more (level `min_depth` of the package's level order) and the voxels
// they cross, as a file of their own: `m` gets their counts, the grid moved by whole voxels to their bounds (.vxl
// spec §7 step 5 ties the grid to the bounds), and `coords` the voxels' coordinates in it.
void keep_level(std::uint32_t min_depth, std::span<const std::uint8_t> depths, MetaSection& m,
                std::vector<std::array<std::int32_t, 3>>& coords, UnpackStructure& s) {
  std::vector<std::uint64_t> strm{0};
  std::vector<VoxlineEntry> voxlines;
  std::vector<std::uint32_t> new_voxel(coords.size(), ~0u);
  std::uint64_t connecting = 0;  // vertices: each voxline but a streamline's last brings a connecting one
  for (std::uint64_t st = 0; st + 1 < s.strm.size(); ++st) {
    if (depths[st] < min_depth) continue;
    for (std::uint64_t j = s.strm[st]; j < s.strm[st + 1]; ++j) {
      voxlines.push_back(s.voxlines[j]);
      new_voxel[s.voxlines[j].voxel] = 0;
    }
    connecting += s.strm[st + 1] - s.strm[st] - (s.strm[st + 1] > s.strm[st]);
    strm.push_back(voxlines.size());
  }
  std::vector<std::array<std::int32_t, 3>> kept;
  std::array<std::int32_t, 3> low{INT32_MAX, INT32_MAX, INT32_MAX}, high{0, 0, 0};
  for (std::size_t i = 0; i < coords.size(); ++i) {
    if (new_voxel[i] != 0) continue;
    new_voxel[i] = static_cast<std::uint32_t>(kept.size());
    kept.push_back(coords[i]);
    for (int c = 0; c < 3; ++c) {
      low[c] = std::min(low[c], coords[i][c]);
      high[c] = std::max(high[c], coords[i][c]);
    }
  }
  for (VoxlineEntry& v : voxlines) v.voxel = new_voxel[v.voxel];
  for (auto& xyz : kept)
    for (int c = 0; c < 3; ++c) xyz[c] -= low[c];
  for (int c = 0; c < 3 && !kept.empty(); ++c) {
    m.grid_origin[c] += double(low[c]) * m.voxel_size;
    m.grid_dims[c] = high[c] - low[c] + 1;
  }
  m.streamline_count = strm.size() - 1;
  m.voxline_count = voxlines.size();
  m.voxel_count = static_cast<std::uint32_t>(kept.size());
  std::uint64_t points = 0, synthetic = 0;
  for (const VoxlineEntry& v : voxlines) {
    points += v.count_flags & kVoxlineCountMask;
    synthetic += v.count_flags >> 31;
  }
  m.point_count = points - synthetic;
  m.synthetic_point_count = synthetic;
  m.vertex_count = points + connecting;
  m.segment_count = m.vertex_count - voxlines.size();
  s.strm = std::move(strm);
  s.voxlines = std::move(voxlines);
  coords = std::move(kept);
}

// `m`: META's counts to check the tables against; with min_depth > 0, set to those of the level kept (keep_level).
UnpackStructure rebuild_structure(const VxlzFile& f, std::uint32_t level_count, std::uint32_t min_depth,
                                  MetaSection& m) {
  const PackSection& k = f.pack();
  const std::string& p = f.path();
  UnpackStructure s;
  s.level_count = level_count;
  auto coords =
      decode_voxel_coords(f.inflate(section_id("VOXC")), m.voxel_count, m.grid_dims, f.context(section_id("VOXC")));
  s.strm = decode_streamline_voxlines(f.inflate(section_id("STRL")), m.streamline_count, m.voxline_count,
                                      f.context(section_id("STRL")));
  s.voxlines = read_voxlines(f, coords);
  std::vector<std::uint8_t> depths = shipped_depths(k, f.meta().streamline_count);
  if (min_depth > 0) {
    keep_level(min_depth, depths, m, coords, s);
    std::erase_if(depths, [&](std::uint8_t d) { return d < min_depth; });
  }

  const std::uint64_t vxlc_at = f.context(section_id("VXLC")).section_offset;
  const std::uint64_t l = m.voxline_count;
  s.starts_streamline.assign(l + 1, 0);
  s.starts_streamline[l] = 1;
  for (std::uint64_t j = 0; j < m.streamline_count; ++j) {
    if (s.strm[j] == s.strm[j + 1]) continue;
    s.starts_streamline[s.strm[j]] = 1;
    if (s.voxlines[s.strm[j]].count_flags & kVoxlineSyntheticFirst)
      fail_input(p, vxlc_at, "streamline " + std::to_string(j) + " starts with a synthetic point");
  }

  // One walk: every voxline's place among its voxel's voxlines of its streamline's depth (spec §5.12), the
  // counts per voxel and depth, the chunk starts, the totals. Streamline by streamline: the depth is the
  // streamline's.
  const std::uint32_t levels = level_count;
  std::vector<std::uint64_t> vertex_count(std::uint64_t(m.voxel_count) * levels, 0),
      voxline_count(std::uint64_t(m.voxel_count) * levels, 0);
  s.offset_in_voxel.resize(l);
  std::uint64_t points = 0, synthetic = 0;
  auto for_each_voxline = [&](auto&& body) {
    for (std::uint64_t st = 0; st < m.streamline_count; ++st) {
      const std::uint32_t depth = streamline_depth(st, levels);
      for (std::uint64_t j = s.strm[st]; j < s.strm[st + 1]; ++j) body(j, depth);
    }
  };
  for_each_voxline([&](std::uint64_t j, std::uint32_t depth) {
    const VoxlineEntry& e = s.voxlines[j];
    const std::uint64_t own = e.count_flags & kVoxlineCountMask;
    std::uint64_t& count = vertex_count[std::uint64_t(e.voxel) * levels + depth];
    if (count + own + s.connected(j) > 0xFFFFFFFFu)
      fail_input(p, vxlc_at, "voxel " + std::to_string(e.voxel) + " gets 2^32 or more vertices");
    if (own > k.point_count - points)
      fail_input(p, vxlc_at, "voxlines hold more points than PACK's point count " + std::to_string(k.point_count));
    s.offset_in_voxel[j] = static_cast<std::uint32_t>(count);  // within its depth, for now
    count += own + s.connected(j);
    voxline_count[std::uint64_t(e.voxel) * levels + depth] += 1;
    points += own;
    synthetic += e.count_flags >> 31;
  });
  std::uint64_t vertices = 0;
  s.voxels.resize(m.voxel_count);
  s.levels.resize(std::uint64_t(m.voxel_count) * (levels - 1));
  // depth_start[i * levels + d]: where depth d's voxlines begin in voxel i's block (after the deeper ones).
  std::vector<std::uint32_t> depth_start(std::uint64_t(m.voxel_count) * levels, 0);
  for (std::uint32_t i = 0; i < m.voxel_count; ++i) {
    std::uint64_t prefix_vertices = 0, prefix_segments = 0;
    for (std::uint32_t d = levels; d-- > 0;) {
      depth_start[std::uint64_t(i) * levels + d] = static_cast<std::uint32_t>(prefix_vertices);
      prefix_vertices += vertex_count[std::uint64_t(i) * levels + d];
      prefix_segments += vertex_count[std::uint64_t(i) * levels + d] - voxline_count[std::uint64_t(i) * levels + d];
      if (prefix_vertices > 0xFFFFFFFFu)
        fail_input(p, vxlc_at, "voxel " + std::to_string(i) + " gets 2^32 or more vertices");
      if (d > 0)
        s.levels[std::uint64_t(i) * (levels - 1) + d - 1] = {static_cast<std::uint32_t>(prefix_vertices),
                                                             static_cast<std::uint32_t>(prefix_segments)};
    }
    if (prefix_vertices < 1) fail_input(p, vxlc_at, "voxel " + std::to_string(i) + " gets no vertices");
    VoxelEntry& v = s.voxels[i];
    v = {};
    std::copy(coords[i].begin(), coords[i].end(), v.coord);
    v.vertex_first = vertices;
    v.vertex_count = static_cast<std::uint32_t>(prefix_vertices);
    v.segment_count = static_cast<std::uint32_t>(prefix_segments);
    vertices += prefix_vertices;
  }
  for_each_voxline([&](std::uint64_t j, std::uint32_t depth) {
    s.offset_in_voxel[j] += depth_start[std::uint64_t(s.voxlines[j].voxel) * levels + depth];
  });
  auto expect = [&](const char* what, std::uint64_t got, std::uint64_t meta_value) {
    if (got != meta_value)
      fail_input(p, vxlc_at,
                 std::string("voxlines give ") + std::to_string(got) + " " + what + " but META says " +
                     std::to_string(meta_value));
  };
  expect("vertices", vertices, m.vertex_count);
  expect("segments", vertices - l, m.segment_count);
  expect("synthetic points", synthetic, m.synthetic_point_count);
  expect("source points", points - synthetic, m.point_count);
  expect("shipped points", points, min_depth > 0 ? points : k.point_count);
  s.order_bytes = layout_orders(s.voxels, s.levels, levels, m.stored_order_count);
  s.order = shipping_order(s.strm, s.voxlines, depths);
  s.shipped_points = points;
  return s;
}

// The shipped PROV with the package's parameters added (spec §7 step 6).
std::string provenance_with_package(const VxlzFile& f) {
  nlohmann::json j = nlohmann::json::object();
  if (f.has_section(section_id("PROV"))) {
    const std::vector<std::uint8_t> raw = f.inflate(section_id("PROV"));
    j = parse_json({reinterpret_cast<const char*>(raw.data()), raw.size()}, f.path(), std::nullopt, "PROV");
    if (j.is_discarded() || !j.is_object())
      fail_input(f.path(), f.context(section_id("PROV")).section_offset, "PROV is not a JSON object");
  }
  const PackSection& k = f.pack();
  j["vxlz"] = {{"package", std::filesystem::path(f.path()).filename().string()},
               {"bits", k.quantization_bits},
               {"quantum_mm", k.quantum},
               {"range_mm", k.range},
               {"error_bound_mm", k.error_bound},
               {"max_error_mm", k.max_error},
               {"rms_error_mm", k.rms_error}};
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

// The value sets as the .vxl lays them out (spec §7 step 8): per vertex, each voxline's own values at
// its own vertices and, at its connecting vertex, a copy of the next voxline's first value (as the
// positions); per streamline, as shipped.
void write_point_values(const UnpackStructure& s, const std::vector<NamedValues>& sets, std::span<std::uint8_t> payload,
                        std::uint64_t vertex_count, unsigned threads) {
  std::vector<std::string> names;
  for (const NamedValues& v : sets) names.push_back(v.name);
  const std::vector<std::span<float>> arrays = layout_value_sets(payload, names, vertex_count);
  parallel_for(sets.size(), threads, [&](std::uint64_t k, unsigned) {
    const float* shipped = sets[k].values.data();
    std::uint64_t point = 0;
    for (std::uint64_t j = 0; j < s.voxlines.size(); ++j) {
      const std::uint64_t own = s.voxlines[j].count_flags & kVoxlineCountMask;
      float* dst = arrays[k].data() + s.first_vertex(j);
      std::copy(shipped + point, shipped + point + own, dst);
      point += own;
      if (s.connected(j)) dst[own] = shipped[point];
    }
  });
  finish_value_sets(payload);
}

void write_streamline_values(const std::vector<NamedValues>& sets, std::span<std::uint8_t> payload,
                             std::uint64_t count) {
  std::vector<std::string> names;
  for (const NamedValues& v : sets) names.push_back(v.name);
  const std::vector<std::span<float>> arrays = layout_value_sets(payload, names, count);
  for (std::size_t k = 0; k < sets.size(); ++k)
    std::copy(sets[k].values.begin(), sets[k].values.end(), arrays[k].begin());
  finish_value_sets(payload);
}

// GDAT (package spec §4.8): the .vxl payload, deflated. Checked as a .vxl reader checks it, against the
// package's groups, so that the .vxl written opens.
std::vector<std::uint8_t> unpacked_group_values(const VxlzFile& f, std::uint64_t group_count) {
  const StreamContext context = f.context(section_id("GDAT"));
  std::vector<std::uint8_t> raw = f.inflate(section_id("GDAT"));
  (void)decode_group_values(raw, group_count, [&](std::uint64_t pos, const std::string& what) {
    fail_input(context.file, context.section_offset,
               "section GDAT, inflated byte " + std::to_string(pos) + ": " + what);
  });
  return raw;
}

// What a package carries besides the positions and the tables: groups, their values and the value sets.
struct PackageExtras {
  std::vector<std::uint8_t> groups_bytes;        // GRPS's .vxl payload
  std::vector<std::uint8_t> group_values_bytes;  // GDAT's
  std::vector<NamedValues> point_values, streamline_values;
};

// The groups and their values as the .vxl's GRPS and GDAT payloads (empty without the sections). GDAT travels as the
// .vxl payload (package spec §4.8): checked against the groups, written back as it came.
void read_groups(const VxlzFile& f, std::vector<std::uint8_t>& groups_bytes,
                 std::vector<std::uint8_t>& group_values_bytes) {
  std::uint64_t group_count = 0;
  if (f.has_section(section_id("GRPS"))) {
    const std::vector<StreamlineGroup> groups =
        decode_group_stream(f.inflate(section_id("GRPS")), f.meta().streamline_count, f.context(section_id("GRPS")));
    group_count = groups.size();
    groups_bytes = encode_groups(groups);
  }
  if (f.has_section(section_id("GDAT"))) group_values_bytes = unpacked_group_values(f, group_count);
}

PackageExtras read_extras(const VxlzFile& f, unsigned threads) {
  PackageExtras extras;
  read_groups(f, extras.groups_bytes, extras.group_values_bytes);

  // Value sets (spec §4.7), checked against PACK's and META's counts before anything is inflated.
  if (f.has_section(section_id("PVAL")))
    extras.point_values = decode_value_section(f.section_payload(section_id("PVAL")), f.pack().point_count,
                                               f.context(section_id("PVAL")), threads);
  if (f.has_section(section_id("SVAL")))
    extras.streamline_values = decode_value_section(f.section_payload(section_id("SVAL")), f.meta().streamline_count,
                                                    f.context(section_id("SVAL")), threads);
  return extras;
}

// What the .vxl's sections take besides the structure's (spec §7 steps 6-8): the groups, their values, the value sets.
struct ExtraSizes {
  std::uint64_t groups = 0, group_values = 0;
  std::uint32_t point_sets = 0, streamline_sets = 0;
};

ExtraSizes sizes_of(const PackageExtras& extras) {
  return {extras.groups_bytes.size(), extras.group_values_bytes.size(),
          static_cast<std::uint32_t>(extras.point_values.size()),
          static_cast<std::uint32_t>(extras.streamline_values.size())};
}

// The same without the values decoded: a value section's set count is its first word (package spec §4.7).
ExtraSizes extra_sizes(const VxlzFile& f) {
  ExtraSizes sizes;
  std::vector<std::uint8_t> groups, group_values;  // small beside the values, which are not decoded
  read_groups(f, groups, group_values);
  sizes.groups = groups.size();
  sizes.group_values = group_values.size();
  auto set_count = [&](const char(&id)[5]) -> std::uint32_t {
    if (!f.has_section(section_id(id))) return 0;
    const std::span<const std::uint8_t> payload = f.section_payload(section_id(id));
    std::uint32_t count = 0;
    if (payload.size() >= 4) std::memcpy(&count, payload.data(), 4);
    if (count < 1 || count > kMaxValueSets)
      fail_input(f.path(), f.context(section_id(id)).section_offset,
                 std::string(id) + " says " + std::to_string(count) + " value sets (1 to " +
                     std::to_string(kMaxValueSets) + ")");
    return count;
  };
  sizes.point_sets = set_count("PVAL");
  sizes.streamline_sets = set_count("SVAL");
  return sizes;
}

// Sets META's bounds from the voxels' tight bounds (package spec §7 step 1), and refuses what a damaged
// package would make: a grid, or positions decoded outside their voxels, that open() refuses.
void set_bounds_checked(MetaSection& meta, std::span<const VoxelEntry> voxels, const std::string& path) {
  // The global bounds (step 1).
  for (int c = 0; c < 3; ++c) {
    meta.bounds_min[c] = meta.bounds_max[c] = 0;
    for (std::size_t i = 0; i < voxels.size(); ++i) {
      meta.bounds_min[c] =
          i == 0 ? voxels[i].tight_min[c] : std::min<double>(meta.bounds_min[c], voxels[i].tight_min[c]);
      meta.bounds_max[c] =
          i == 0 ? voxels[i].tight_max[c] : std::max<double>(meta.bounds_max[c], voxels[i].tight_max[c]);
    }
  }
  // A damaged package's grid, or positions it decodes outside their voxels, would make a file open() refuses.
  check_grid_geometry(meta, path, std::nullopt);
  for (std::size_t i = 0; i < voxels.size(); ++i)
    for (int c = 0; c < 3; ++c)
      if (!tight_bounds_in_place(meta, voxels[i], c))
        fail_input(path, std::nullopt,
                   "the positions decode outside their voxels: " + misplaced_voxel(meta, voxels[i], i, c));
}

// The sections after VERT and ORDB (spec §7 steps 6-8): META with its bounds, the directions, the voxel and level
// tables, the voxline and streamline tables with their voxel index, the lengths, PROV, and what the package carries
// besides (groups, their values, the value sets).
void append_tables(VxlStreamWriter& out, std::span<const DirectionEntry> directions, const UnpackStructure& s,
                   const MetaSection& meta, std::span<const VoxelEntry> voxels, std::span<const float> lengths,
                   const std::string& provenance, const PackageExtras& extras, unsigned threads) {
  out.append_meta(meta);
  out.append_items<DirectionEntry>(VxlStreamWriter::kDirs, directions);
  out.append_items<VoxelEntry>(VxlStreamWriter::kVoxt, voxels);
  if (!s.levels.empty()) out.append_items<LevelEntry>(VxlStreamWriter::kLods, s.levels);
  out.append_items<VoxlineEntry>(VxlStreamWriter::kVxln, s.voxlines);
  out.append_items<std::uint64_t>(VxlStreamWriter::kStrm, s.strm);
  if (const std::uint64_t bytes = voxel_index_bytes(meta); bytes > 0) {
    std::vector<std::uint8_t> payload(bytes);
    fill_voxel_index_payload(payload, s.strm, s.voxlines);
    out.append(VxlStreamWriter::kVxix, payload);
  }
  if (!lengths.empty()) out.append_items<float>(VxlStreamWriter::kSlen, lengths);
  out.append(VxlStreamWriter::kProv, {reinterpret_cast<const std::uint8_t*>(provenance.data()), provenance.size()});
  if (!extras.groups_bytes.empty()) out.append(VxlStreamWriter::kGrps, extras.groups_bytes);
  if (!extras.point_values.empty()) {
    std::vector<std::uint8_t> payload(value_sets_bytes(extras.point_values.size(), meta.vertex_count), 0);
    write_point_values(s, extras.point_values, payload, meta.vertex_count, threads);
    out.append(VxlStreamWriter::kVval, payload);
  }
  if (!extras.streamline_values.empty()) {
    std::vector<std::uint8_t> payload(value_sets_bytes(extras.streamline_values.size(), meta.streamline_count), 0);
    write_streamline_values(extras.streamline_values, payload, meta.streamline_count);
    out.append(VxlStreamWriter::kSval, payload);
  }
  if (!extras.group_values_bytes.empty()) out.append(VxlStreamWriter::kGdat, extras.group_values_bytes);
}

// Lets go of what only the positions needed: the shipping order, and unless the point values are laid out as the
// positions (write_point_values) each voxline's place and streamline start (for 1M streamlines 37 MB in all), before
// the tables after ORDB take their memory.
void let_go_of_decoding_tables(UnpackStructure& s, const PackageExtras& extras) {
  s.order = ShippingOrder();
  if (!extras.point_values.empty()) return;
  s.starts_streamline = std::vector<std::uint8_t>();
  s.offset_in_voxel = std::vector<std::uint32_t>();
}

// Then lets go of the rest the tables after ORDB needed (the orders read the voxel and level tables alone): for 1M
// streamlines about 80 MB, which the orders' buffers then reuse.
void let_go_of_voxline_tables(UnpackStructure& s, std::vector<float>& lengths, PackageExtras& extras) {
  // Assigned new vectors (`= {}` would clear them and keep their memory).
  s.strm = std::vector<std::uint64_t>();
  s.voxlines = std::vector<VoxlineEntry>();
  s.starts_streamline = std::vector<std::uint8_t>();  // kept until now for point values
  s.offset_in_voxel = std::vector<std::uint32_t>();
  lengths = std::vector<float>();
  extras = PackageExtras();
}

// Refuses settings the package cannot meet, and rebuilds its tables (`meta`: the .vxl's counts, those of the level
// alone with settings.level).
UnpackStructure checked_structure(const VxlzFile& f, const UnpackSettings& settings, MetaSection& meta) {
  const std::uint32_t levels = settings.levels == 0 ? package_levels(f) : settings.levels;
  detail::check_level_count(levels, f.path());
  if (f.meta().order_set == static_cast<std::uint32_t>(OrderSet::Random))
    fail_unsupported(f.path(), "per-voxel random order sets are not part of package format 2.0");
  const bool level_alone = settings.level > 0;
  if (level_alone && (f.pack().predictor != kVxlzPredictorLinearLevelOrder || settings.level >= f.pack().level_count))
    throw Error(ErrorKind::Usage, f.path(), std::nullopt,
                "level " + std::to_string(settings.level) + " is not shipped apart in this package (" +
                    (f.pack().level_count > 1 ? std::to_string(f.pack().level_count) + " levels" : "no level order") +
                    ")");
  // A level alone is a file of its own, without levels: its counts are set by keep_level.
  return rebuild_structure(f, level_alone ? 1 : levels, settings.level, meta);
}

// The .vxl's section sizes (and META's encoding and level count, set in `meta`).
VxlSectionSizes unpacked_section_sizes(MetaSection& meta, const UnpackStructure& s, const UnpackSettings& settings,
                                       std::uint64_t provenance_bytes, const ExtraSizes& extra) {
  meta.position_encoding = static_cast<std::uint32_t>(settings.positions);
  meta.level_count = s.level_count > 1 && meta.voxel_count > 0 ? s.level_count : 0;
  VxlSectionSizes sizes =
      section_sizes(meta, s.order_bytes, provenance_bytes, extra.groups, extra.point_sets, extra.streamline_sets);
  sizes.group_values = extra.group_values;
  return sizes;
}

// The unpack; let_go_of_package() is called once the positions are decoded, after which `f` is not read.
UnpackSummary unpack(const VxlzFile& f, const std::string& out_path, const UnpackSettings& settings,
                     const std::function<void()>& let_go_of_package) {
  using Clock = std::chrono::steady_clock;
  auto seconds_since = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  const unsigned threads = resolve_threads(settings.threads);
  auto progress = [&](const char* stage, double fraction) {
    if (settings.progress) settings.progress(stage, fraction);
  };
  UnpackSummary summary;
  auto t0 = Clock::now();
  progress("decoding", 0.0);

  MetaSection meta = f.meta();
  UnpackStructure s = checked_structure(f, settings, meta);
  const std::string provenance = provenance_with_package(f);
  const std::vector<DirectionEntry> directions(f.directions().begin(), f.directions().end());
  summary.pack = f.pack();
  // A level alone is for a first look: the groups and value sets come with the whole.
  PackageExtras extras = settings.level > 0 ? PackageExtras() : read_extras(f, threads);
  summary.point_value_sets = static_cast<std::uint32_t>(extras.point_values.size());
  summary.streamline_value_sets = static_cast<std::uint32_t>(extras.streamline_values.size());
  const VxlSectionSizes sizes = unpacked_section_sizes(meta, s, settings, provenance.size(), sizes_of(extras));
  // The same stages as a conversion's last: VERT filled in place (or block by block), the tables after ORDB, then the
  // orders a chunk of voxels at a time (write_range_orders, one range of every voxel): the writer takes the sections
  // in any order, and the tables' memory is let go before the orders take theirs. A refused package leaves no file.
  VxlStreamWriter out(out_path, sizes, kSectionDirectStagingBytes);
  std::vector<VoxelEntry>& voxels = s.voxels;  // their tight bounds set from the decoded vertices
  std::vector<float> lengths(meta.streamline_count);
  VoxlineEnds ends(meta.vertex_count);
  VoxelRange whole = whole_range(voxels);
  whole.order_threads = threads;
  const bool packed = settings.positions == PositionEncoding::Packed;
  const std::uint64_t memory_allowed =
      settings.memory_limit > 0 ? settings.memory_limit : available_memory().value_or(1ull << 30) / 2;
  // Block by block where the shipping order fills each (voxel, depth) block from its first vertex on: streamline order
  // does for any levels, level order for at least the levels it ships by (with fewer, the coarsest block gathers
  // several shipped depths, whose streamlines then interleave).
  const bool fills_blocks_in_order =
      f.pack().predictor != kVxlzPredictorLinearLevelOrder || s.level_count >= f.pack().level_count;
  const std::uint64_t block_staging = packed && settings.level == 0 && fills_blocks_in_order &&
                                              (settings.vertex_blocks || sizes.vertices > memory_allowed / 2)
                                          ? vertex_block_staging_bytes(s, f.pack(), sizes.vertices, memory_allowed)
                                          : 0;
  summary.vertices_read_back = block_staging > 0;
  summary.decoded_twice = summary.vertices_read_back || (packed && 12 * meta.vertex_count > memory_allowed);
  // The stage's progress: a pass's fraction d from `from` on, over `part` of it.
  const auto decoding = [&](double from, double part) {
    return [&, from, part](double d) { progress("decoding", from + d * part); };
  };
  OrderSetSpec order_set;
  order_set.kind = static_cast<OrderSet>(meta.order_set);
  for (const DirectionEntry& d : directions) order_set.directions.push_back({d.xyz[0], d.xyz[1], d.xyz[2]});
  RangeOrderSettings orders;
  orders.order_set = &order_set;
  orders.positions = settings.positions;
  orders.order_chunk_bytes = order_chunk_bytes(voxels, s.order_bytes, threads, 0, s.order_bytes);
  orders.direct = true;
  orders.float_ends = &ends;
  orders.progress = [&](double d) { progress("ordering", d); };
  const OrderedTable table{voxels, s.levels, s.level_count, s.order_bytes};
  const auto write_tables = [&] {
    let_go_of_package();
    let_go_of_decoding_tables(s, extras);
    const auto t = Clock::now();
    progress("writing", 0.0);
    append_tables(out, directions, s, meta, voxels, lengths, provenance, extras, threads);
    let_go_of_voxline_tables(s, lengths, extras);
    summary.write_seconds += seconds_since(t);
  };
  if (summary.vertices_read_back) {
    scan_positions(f, s, ends, lengths, threads, decoding(0, 0.5));
    set_bounds_checked(meta, voxels, f.path());
    summary.repack_error_bound = write_positions_in_blocks(f, s, ends, out, block_staging, decoding(0.5, 0.5));
    summary.decode_seconds = seconds_since(t0);
    write_tables();
    const OrdersPool pool_sizes = orders_pool(voxels, s.order_bytes, settings.positions, orders.order_chunk_bytes);
    void* const pool = std::aligned_alloc(DirectRegionWriter::kBlock, pool_sizes.total());
    if (pool == nullptr) throw std::bad_alloc();
    const std::unique_ptr<std::uint8_t, void (*)(void*)> pool_owner(static_cast<std::uint8_t*>(pool), std::free);
    orders.pool = pool_owner.get();
    orders.pool_chunk_bytes = pool_sizes.chunk_bytes;
    orders.pool_read_back_bytes = pool_sizes.read_back_bytes;
    summary.orders_seconds = write_range_orders(out, table, whole, {}, orders);
  } else {
    const auto place = [&](std::span<std::uint8_t> window) {
      const std::span<std::uint32_t> words(reinterpret_cast<std::uint32_t*>(window.data()), window.size() / 4);
      // Where the first pass keeps the decoded positions: a float32 file's VERT; for a packed one, floats within the
      // memory limit. Left uninitialised: the chunks write every vertex (rebuild_structure checked that the
      // voxlines' points are the package's), and zeroing them first cost a serial pass over fresh pages (0.3 s for
      // 1M streamlines).
      std::unique_ptr<float[]> kept;
      if (packed && !summary.decoded_twice)
        kept.reset(new float[3 * words.size()]);  // a packed file's words: one a vertex
      float* const keep = packed ? kept.get() : reinterpret_cast<float*>(window.data());
      scan_positions(f, s, ends, lengths, threads, decoding(0, summary.decoded_twice ? 0.5 : 1), keep);
      set_bounds_checked(meta, voxels, f.path());
      if (summary.decoded_twice)
        summary.repack_error_bound = write_positions(f, s, ends, words, threads, decoding(0.5, 0.5));
      else if (packed)
        summary.repack_error_bound = pack_kept_positions(s, {kept.get(), 3 * words.size()}, ends, words, threads);
      summary.decode_seconds = seconds_since(t0);
    };
    const auto order = [&](std::span<const std::uint8_t> window) {
      write_tables();
      summary.orders_seconds = write_range_orders(out, table, whole, window, orders);
    };
    out.append_in_place(VxlStreamWriter::kVert, sizes.vertices, threads, place, order);
  }

  t0 = Clock::now();
  out.commit();
  summary.write_seconds += seconds_since(t0);
  progress("writing", 1.0);

  summary.streamlines = meta.streamline_count;
  summary.points = meta.point_count;
  summary.voxels = meta.voxel_count;
  return summary;
}

}  // namespace

std::uint32_t package_levels(const VxlzFile& f) {
  if (f.pack().predictor == kVxlzPredictorLinearLevelOrder) return f.pack().level_count;
  // Streamline order: written for a file without levels, or by a writer older than 2.3 for any file. Neither
  // says how many the file had; the levels its conversion asked for (PROV, spec §5.8) do.
  if (f.has_section(section_id("PROV"))) {
    const std::vector<std::uint8_t> raw = f.inflate(section_id("PROV"));
    const nlohmann::json prov =
        parse_json({reinterpret_cast<const char*>(raw.data()), raw.size()}, f.path(), std::nullopt, "PROV");
    if (prov.is_object() && prov.contains("converter") && prov["converter"].is_object()) {
      const nlohmann::json& levels = prov["converter"].value("levels", nlohmann::json());
      if (levels.is_number_unsigned() && levels.get<std::uint64_t>() >= 1 && levels.get<std::uint64_t>() <= kMaxLevels)
        return levels.get<std::uint32_t>();
    }
  }
  return kDefaultLevels;
}

UnpackSummary unpack_vxlz(const std::string& in_path, const std::string& out_path, const UnpackSettings& settings) {
  if (settings.levels != 0) detail::check_level_count(settings.levels, in_path);
  return unpack_vxlz(VxlzFile::open(in_path), out_path, settings);
}

UnpackSummary unpack_vxlz(const VxlzFile& package, const std::string& out_path, const UnpackSettings& settings) {
  return unpack(package, out_path, settings, [] {});
}

UnpackSummary unpack_vxlz(VxlzFile&& package, const std::string& out_path, const UnpackSettings& settings) {
  std::optional<VxlzFile> held(std::move(package));
  return unpack(*held, out_path, settings, [&] { held.reset(); });
}

std::uint64_t unpacked_vxl_bytes(const VxlzFile& f, const UnpackSettings& settings) {
  MetaSection meta = f.meta();
  const UnpackStructure s = checked_structure(f, settings, meta);
  const ExtraSizes extra = settings.level > 0 ? ExtraSizes() : extra_sizes(f);
  return plan_vxl_layout(unpacked_section_sizes(meta, s, settings, provenance_with_package(f).size(), extra)).file_size;
}

std::vector<ShippedLevel> shipped_levels(const VxlzFile& f) {
  const PackSection& k = f.pack();
  if (k.predictor != kVxlzPredictorLinearLevelOrder) return {};
  const MetaSection& m = f.meta();
  const std::vector<std::uint64_t> strm = decode_streamline_voxlines(f.inflate(section_id("STRL")), m.streamline_count,
                                                                     m.voxline_count, f.context(section_id("STRL")));
  const std::vector<std::uint8_t> counts = f.inflate(section_id("VXLC"));
  check_stream_holds_voxlines(f, section_id("VXLC"), counts);
  std::vector<VoxlineEntry> voxlines(static_cast<std::size_t>(m.voxline_count));
  decode_voxline_counts(counts, voxlines, f.context(section_id("VXLC")));
  std::vector<std::uint64_t> streamlines(k.level_count, 0), points(k.level_count, 0);
  for (std::uint64_t st = 0; st < m.streamline_count; ++st) {
    const std::uint32_t d = streamline_depth(st, k.level_count);
    streamlines[d] += 1;
    for (std::uint64_t j = strm[st]; j < strm[st + 1]; ++j) points[d] += voxlines[j].count_flags & kVoxlineCountMask;
  }
  std::vector<ShippedLevel> levels;
  ShippedLevel sum;
  for (std::uint32_t d = k.level_count; d-- > 0;) {
    sum.level = d;
    sum.streamlines += streamlines[d];
    sum.points += points[d];
    // Points beyond PACK's count are refused when decoded; here they only ask for every chunk.
    sum.bytes = f.chunks_end(std::min(k.chunk_count, (sum.points + k.chunk_points - 1) / k.chunk_points));
    levels.push_back(sum);
  }
  return levels;
}

}  // namespace vxl
