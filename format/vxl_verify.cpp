#include "format/vxl_verify.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include <nlohmann/json.hpp>

#include "format/base/checksum.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/streamline_length.h"
#include "format/voxel_voxlines.h"
#include "format/vxl_file.h"
#include "format/vxl_positions.h"
#include "format/vxl_streamlines.h"

namespace vxl {
namespace {

void check_checksums_and_padding(const VxlFile& f) {
  const std::string& p = f.path();
  auto bytes = f.bytes();
  FileHeader h = f.header();
  h.header_checksum = 0;
  const std::uint64_t table_end = sizeof(FileHeader) + f.sections().size_bytes();
  std::vector<std::uint8_t> head(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(table_end));
  std::memcpy(head.data(), &h, sizeof h);
  if (xxh3_64(head.data(), head.size()) != f.header().header_checksum)
    fail_input(p, 40, "header checksum mismatch (header or section table damaged)");
  if (!all_zero(f.header().reserved, sizeof f.header().reserved))
    fail_input(p, 48, "reserved header bytes are not zero");

  std::vector<std::pair<std::uint64_t, std::uint64_t>> covered = {{0, table_end}};
  for (const SectionEntry& e : f.sections()) {
    if (xxh3_64(bytes.data() + e.offset, e.size) != e.checksum)
      fail_input(p, e.offset, "checksum mismatch in section " + std::string(e.id, 4));
    covered.push_back({e.offset, e.offset + e.size});
  }
  std::sort(covered.begin(), covered.end());
  std::uint64_t pos = 0;
  for (auto [begin, end] : covered) {
    if (begin > pos && !all_zero(bytes.data() + pos, begin - pos)) fail_input(p, pos, "padding bytes are not zero");
    pos = std::max(pos, end);
  }
  if (pos < bytes.size() && !all_zero(bytes.data() + pos, bytes.size() - pos))
    fail_input(p, pos, "padding bytes are not zero");
}

void check_meta_and_dirs(const VxlFile& f) {
  const std::string& p = f.path();
  const MetaSection& m = f.meta();
  const std::uint64_t meta_at = f.find_section(section_id("META"))->offset;
  if (!all_zero(m.reserved, sizeof m.reserved)) fail_input(p, meta_at + 160, "META reserved bytes are not zero");
  auto check_unit = [&](std::span<const DirectionEntry> dirs, const char(&id)[5]) {
    const std::uint64_t at = f.find_section(section_id(id))->offset;
    for (std::size_t k = 0; k < dirs.size(); ++k) {
      const DirectionEntry& d = dirs[k];
      double len = std::sqrt(double(d.xyz[0]) * d.xyz[0] + double(d.xyz[1]) * d.xyz[1] + double(d.xyz[2]) * d.xyz[2]);
      if (d.reserved != 0 || !(std::abs(len - 1.0) < 1e-5))
        fail_input(p, at + 16 * k, std::string(id) + " direction is not a unit vector");
    }
  };
  check_unit(f.directions(), "DIRS");
  if (!f.voxel_directions().empty()) check_unit(f.voxel_directions(), "VDIR");
}

// Every order must be a permutation of the voxel's segments, sorted by the key of spec §6.4 for the
// voxel's own direction (VDIR) or the shared one (DIRS).
void check_orders(const VxlFile& f, const std::vector<std::uint8_t>& is_segment_start) {
  const std::string& p = f.path();
  const std::uint64_t ordr_at = f.orders_offset();
  auto voxels = f.voxels();
  const std::uint64_t vert_at = f.find_section(section_id("VERT"))->offset;
  auto packed = f.packed_vertices();
  std::vector<std::uint8_t> seen;
  std::vector<float> block;
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    const VoxelEntry& v = voxels[i];
    // Packed words: the voxline-end bit exactly where no segment starts, the reserved bit clear (§5.4).
    if (!packed.empty())
      for (std::uint64_t g = v.vertex_first; g < v.vertex_first + v.vertex_count; ++g) {
        const bool end = (packed[g] & kPackedVoxlineEnd) != 0;
        if ((packed[g] & kPackedReservedBit) != 0 || end == (is_segment_start[g] != 0))
          fail_input(p, vert_at + 4 * g,
                     "packed vertex " + std::to_string(g) + ": voxline-end bit wrong or reserved bit set");
      }
    block.resize(3 * std::uint64_t(v.vertex_count));
    f.read_vertices(i, v.vertex_first, v.vertex_count, block.data());
    // Each level: its segment count, and K orders of the segments in its prefix of the block (§5.12).
    for (std::uint32_t level = 0; level < f.level_count(); ++level) {
      const LevelEntry counts = f.level(i, level);
      const std::uint64_t at =
          ordr_at + level_orders_offset(v, f.levels_of(i), level, f.meta().stored_order_count, f.order_packing());
      const std::string what = "voxel " + std::to_string(i) + (level > 0 ? " level " + std::to_string(level) : "");
      std::uint64_t starts = 0;
      for (std::uint32_t e = 0; e < counts.vertex_count; ++e) starts += is_segment_start[v.vertex_first + e];
      if (starts != counts.segment_count)
        fail_input(p, f.find_section(section_id("VOXT"))->offset + 64 * i,
                   what + " segment count does not match its voxlines");
      for (std::uint32_t k = 0; k < f.meta().stored_order_count; ++k) {
        const DirectionEntry& dir = f.directions_of(i)[k];
        OrderView o = f.order(i, k, level);
        seen.assign(counts.vertex_count, 0);
        double previous_key = -INFINITY;
        std::uint32_t previous_entry = 0;
        for (std::uint32_t n = 0; n < o.count; ++n) {
          std::uint32_t e = o[n];
          if (e + 1ull >= counts.vertex_count || !is_segment_start[v.vertex_first + e] || seen[e])
            fail_input(p, at, what + " order " + std::to_string(k) + " is not a permutation of its segments");
          seen[e] = 1;
          const float* a = block.data() + 3 * std::uint64_t(e);
          double key = 0;
          for (int c = 0; c < 3; ++c) key += (double(a[c]) + double(a[c + 3])) * double(dir.xyz[c]);
          if (n > 0 && (key < previous_key || (key == previous_key && e < previous_entry)))
            fail_input(p, at, what + " order " + std::to_string(k) + " is not sorted");
          previous_key = key;
          previous_entry = e;
        }
        // ORDB: the bits after the last entry, up to the array's last byte, are zero (§5.5).
        const std::uint64_t used = std::uint64_t(o.count) * o.bits;
        if (used % 8 != 0 && (o.data[used / 8] >> (used % 8)) != 0)
          fail_input(p, at, what + " order " + std::to_string(k) + " has bits set after its last entry");
      }
      // And the level's padding to 4 bytes.
      const std::uint32_t bits = order_entry_bits(counts.vertex_count, f.order_packing());
      const std::uint64_t arrays = f.meta().stored_order_count * order_array_bytes(counts.segment_count, bits);
      const std::uint64_t padded = level_orders_size(counts, f.meta().stored_order_count, f.order_packing());
      if (!all_zero(f.bytes().data() + at + arrays, padded - arrays))
        fail_input(p, at + arrays, what + " order padding is not zero");
    }
  }
}

// VVAL / SVAL (spec §5.11): reserved fields and every padding byte zero (names, between the entries and
// the arrays, after each array), min and max equal to the arrays' finite extremes.
void check_value_sets(const VxlFile& f, const ValueSets& sets, const char (&id)[5]) {
  if (sets.empty()) return;
  const std::string& p = f.path();
  const std::uint64_t at = f.find_section(section_id(id))->offset;
  const auto bytes = sets.payload();
  ValueSetsHeader h;
  std::memcpy(&h, bytes.data(), sizeof h);
  if (h.reserved != 0) fail_input(p, at + 4, std::string(id) + " reserved field is not zero");
  const std::uint64_t data = value_sets_data_offset(h.set_count), stride = value_array_stride(h.value_count);
  for (std::uint32_t k = 0; k < h.set_count; ++k) {
    const std::uint64_t e_at = sizeof h + k * sizeof(ValueSetEntry);
    ValueSetEntry e;
    std::memcpy(&e, bytes.data() + e_at, sizeof e);
    const std::size_t len = std::strlen(e.name);
    if (!all_zero(reinterpret_cast<const std::uint8_t*>(e.name) + len, sizeof e.name - len) || e.reserved != 0)
      fail_input(p, at + e_at,
                 std::string(id) + " set " + std::to_string(k) + ": name padding or reserved bytes not zero");
    float lo = INFINITY, hi = -INFINITY;
    for (float v : sets.values(k))
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    const bool none = lo > hi;
    if (none ? !(std::isnan(e.min) && std::isnan(e.max)) : (e.min != lo || e.max != hi))
      fail_input(
          p, at + e_at + 48,
          std::string(id) + " set " + std::to_string(k) + " (" + sets.name(k) + "): min/max do not match its values");
    const std::uint64_t end = data + k * stride + 4 * h.value_count;
    if (!all_zero(bytes.data() + end, data + (k + 1) * stride - end))
      fail_input(p, at + end, std::string(id) + " padding after set " + std::to_string(k) + " is not zero");
  }
  const std::uint64_t entries_end = sizeof h + std::uint64_t(h.set_count) * sizeof(ValueSetEntry);
  if (!all_zero(bytes.data() + entries_end, data - entries_end))
    fail_input(p, at + entries_end, std::string(id) + " padding before the arrays is not zero");
}

// VXIX (§5.14): exactly the lists built from VXLN and STRM.
void check_voxel_index(const VxlFile& f) {
  if (f.voxel_index_first().empty()) return;
  const std::optional<VoxelVoxlines> built = VoxelVoxlines::build(f);
  const std::uint64_t at = f.find_section(section_id("VXIX"))->offset;
  if (!built) fail_input(f.path(), at, "VXIX in a file of more than 2^29 streamlines");
  for (std::size_t i = 0; i < f.voxels().size(); ++i) {
    const auto stored = f.voxel_index_entries().subspan(f.voxel_index_first()[i],
                                                        f.voxel_index_first()[i + 1] - f.voxel_index_first()[i]);
    const auto expected = built->of_voxel(i);
    if (stored.size() != expected.size())
      fail_input(f.path(), at + 8 * i, "VXIX list of voxel " + std::to_string(i) + " does not hold its voxlines");
    for (std::size_t k = 0; k < stored.size(); ++k)
      if (stored[k].word != expected[k].word)
        fail_input(
            f.path(), at + 8 * (f.voxels().size() + 1) + 4 * (f.voxel_index_first()[i] + k),
            "VXIX entry " + std::to_string(k) + " of voxel " + std::to_string(i) + " differs from the voxline table");
  }
}

// Tight bounds (§5.3): the extremes of the voxel's vertices, which frustum and slab culling trust. Float32:
// every vertex inside them and each bound reached. Packed (§5.4), where only the words are stored: on every
// axis the words reach the quanta the bounds themselves pack to (0 and, unless the step is 0, 1023).
// META's bounds (§5.1) are the extremes of all vertices, so of the voxels' tight bounds.
void check_bounds(const VxlFile& f) {
  const std::string& p = f.path();
  const std::uint64_t voxt = f.find_section(section_id("VOXT"))->offset;
  const std::uint64_t vert = f.find_section(section_id("VERT"))->offset;
  const bool packed = f.position_encoding() == PositionEncoding::Packed;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (std::size_t i = 0; i < f.voxels().size(); ++i) {
    const VoxelEntry& v = f.voxels()[i];
    bool reached_lo[3] = {false, false, false}, reached_hi[3] = {false, false, false};
    if (packed) {
      const VertexPacker packer(v);
      std::uint32_t want_lo = 0, want_hi = 0;
      packer.words(v.tight_min, 1, &want_lo);
      packer.words(v.tight_max, 1, &want_hi);
      std::uint32_t q_lo[3] = {kPackedAxisMask, kPackedAxisMask, kPackedAxisMask}, q_hi[3] = {0, 0, 0};
      for (std::uint32_t w : f.packed_vertices().subspan(v.vertex_first, v.vertex_count))
        for (int c = 0; c < 3; ++c) {
          q_lo[c] = std::min(q_lo[c], (w >> (10 * c)) & kPackedAxisMask);
          q_hi[c] = std::max(q_hi[c], (w >> (10 * c)) & kPackedAxisMask);
        }
      for (int c = 0; c < 3; ++c) {
        reached_lo[c] = q_lo[c] == ((want_lo >> (10 * c)) & kPackedAxisMask);
        reached_hi[c] = q_hi[c] == ((want_hi >> (10 * c)) & kPackedAxisMask);
      }
    } else {
      const auto xyz = f.float_vertices().subspan(3 * v.vertex_first, 3 * std::uint64_t(v.vertex_count));
      for (std::size_t k = 0; k < xyz.size(); ++k) {
        const int c = static_cast<int>(k % 3);
        if (!(v.tight_min[c] <= xyz[k] && xyz[k] <= v.tight_max[c]))
          fail_input(p, vert + 4 * (3 * v.vertex_first + k),
                     "vertex outside the tight bounds of its voxel " + std::to_string(i));
        reached_lo[c] = reached_lo[c] || xyz[k] == v.tight_min[c];
        reached_hi[c] = reached_hi[c] || xyz[k] == v.tight_max[c];
      }
    }
    for (int c = 0; c < 3; ++c) {
      if (!reached_lo[c] || !reached_hi[c])
        fail_input(p, voxt + 64 * i + (reached_lo[c] ? 28 : 16) + 4 * c,
                   "tight bounds of voxel " + std::to_string(i) + " are not the extremes of its vertices");
      lo[c] = i == 0 ? v.tight_min[c] : std::min<double>(lo[c], v.tight_min[c]);
      hi[c] = i == 0 ? v.tight_max[c] : std::max<double>(hi[c], v.tight_max[c]);
    }
  }
  const std::uint64_t meta = f.find_section(section_id("META"))->offset;
  for (int c = 0; c < 3; ++c)
    if (f.meta().bounds_min[c] != lo[c] || f.meta().bounds_max[c] != hi[c])
      fail_input(p, meta + (f.meta().bounds_min[c] != lo[c] ? 104 : 128) + 8 * c,
                 "META bounds are not the extremes of the voxels' tight bounds");
}

// The grid exactly as large as the points make it (spec §6.1): on every axis some voxel has coordinate 0 (the
// smallest point's) and some grid_dims - 1 (the largest's). open() allows a voxel of slack, which this takes away.
void check_grid_extent(const VxlFile& f) {
  if (f.voxels().empty()) return;
  std::int32_t lo[3] = {INT32_MAX, INT32_MAX, INT32_MAX}, hi[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
  for (const VoxelEntry& v : f.voxels())
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], v.coord[c]), hi[c] = std::max(hi[c], v.coord[c]);
  const std::uint64_t meta = f.find_section(section_id("META"))->offset;
  for (int c = 0; c < 3; ++c)
    if (lo[c] != 0 || hi[c] != f.meta().grid_dims[c] - 1)
      fail_input(f.path(), meta + 88 + 4 * c,
                 "grid_dims or grid_origin do not fit the voxels: their coordinates on " + std::string(1, "xyz"[c]) +
                     " run from " + std::to_string(lo[c]) + " to " + std::to_string(hi[c]) + ", expected 0 to " +
                     std::to_string(f.meta().grid_dims[c] - 1));
}

// SLEN (§5.15): each length against the stored points' length, equal to the bit with float32 positions (they are
// the source points); with packed positions within what moving each point by the file's bound can change.
class LengthCheck {
 public:
  explicit LengthCheck(const VxlFile& f) : f_(f), packed_(f.position_encoding() == PositionEncoding::Packed) {
    if (packed_)
      for (const VoxelEntry& v : f.voxels()) bound_ = std::max(bound_, packed_error_bound(v));
  }
  void operator()(std::uint64_t s, std::span<const float> xyz) const {
    const double stored = stored_length(f_, s), measured = polyline_length(xyz);
    const double segments = xyz.size() / 3 > 1 ? double(xyz.size() / 3 - 1) : 0.0;
    const bool holds = !packed_ ? float(measured) == float(stored)
                                : std::abs(stored - measured) <=
                                      2 * std::sqrt(3.0) * bound_ * segments + 1e-6 * std::max(1.0, measured);
    if (!holds)
      fail_input(f_.path(), f_.find_section(section_id("SLEN"))->offset + 4 * s,
                 "SLEN length of streamline " + std::to_string(s) + " (" + std::to_string(stored) +
                     " mm) differs from its points' (" + std::to_string(measured) + " mm)");
  }

 private:
  const VxlFile& f_;
  bool packed_;
  double bound_ = 0;  // per axis, the largest of the voxels' packing bounds
};

}  // namespace

VerifyResult verify_vxl(const std::string& path) {
  try {
    return verify_vxl(VxlFile::open(path));
  } catch (const Error& e) {
    return VerifyResult::refused(e);
  }
}

VerifyResult verify_vxl(const VxlFile& f) {
  const std::string& path = f.path();
  try {
    check_checksums_and_padding(f);
    check_meta_and_dirs(f);
    check_bounds(f);
    check_grid_extent(f);
    // The walk marks which vertices start a segment (all but each voxline's last vertex).
    std::vector<std::uint8_t> is_segment_start(f.meta().vertex_count, 0);
    WalkCallbacks cb;
    cb.voxline = [&](const VoxlineVisit& v) {
      const std::uint64_t n = v.own_points + (v.connected ? 1 : 0);
      for (std::uint64_t i = 0; i + 1 < n; ++i) is_segment_start[v.first_vertex + i] = 1;
    };
    if (!f.streamline_lengths().empty()) cb.streamline = LengthCheck(f);
    walk_streamlines(f, cb);
    check_orders(f, is_segment_start);
    check_voxel_index(f);
    if (!f.provenance_json().empty() &&
        (parse_json(f.provenance_json(), path, f.provenance_offset(), "provenance").is_discarded()))
      fail_input(path, f.provenance_offset(), "provenance is not valid JSON");
    f.groups();
    check_value_sets(f, f.vertex_values(), "VVAL");
    check_value_sets(f, f.streamline_values(), "SVAL");
  } catch (const Error& e) {
    return VerifyResult::refused(e);
  }
  VerifyResult valid;
  valid.valid = true;
  return valid;
}

}  // namespace vxl
