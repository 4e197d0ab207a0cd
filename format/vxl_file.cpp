#include "format/vxl_file.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>

#include "format/base/checked_count.h"
#include "format/base/checksum.h"
#include "format/base/error.h"
#include "format/base/utf8_check.h"
#include "format/vxlz_layout.h"

namespace vxl {

std::string section_name(std::uint32_t id) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) {
    char c = static_cast<char>((id >> (8 * i)) & 0xFF);
    s[i] = (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

VxlFile VxlFile::open(const std::string& path) { return open(MappedFile(path)); }

VxlFile VxlFile::open(MappedFile bytes) {
  VxlFile f{std::move(bytes)};
  f.validate();
  f.checksum_checked_ = std::make_unique<std::atomic<std::uint8_t>[]>(f.sections_.size());
  return f;
}

std::vector<SectionEntry> VxlFile::read_section_table(const std::string& path, std::span<const std::uint8_t> first,
                                                      std::uint64_t file_size) {
  const std::size_t held = static_cast<std::size_t>(std::min<std::uint64_t>(first.size(), file_size));
  auto* copy = static_cast<std::uint8_t*>(std::malloc(std::max<std::size_t>(held, 1)));
  if (copy == nullptr) throw std::bad_alloc();
  std::memcpy(copy, first.data(), held);
  VxlFile f{MappedFile::adopt(path, copy, held)};
  f.file_size_ = file_size;
  f.validate_header();
  f.validate_section_table();
  return {f.sections_.begin(), f.sections_.end()};
}

void VxlFile::check_section_checksum(std::uint32_t id) const {
  const SectionEntry* e = find_section(id);
  if (!e) return;
  std::atomic<std::uint8_t>& checked = checksum_checked_[static_cast<std::size_t>(e - sections_.data())];
  if (checked.load(std::memory_order_acquire) != 0) return;
  if (xxh3_64(bytes().data() + e->offset, e->size) != e->checksum)
    fail_input(
        path(), e->offset,
        "checksum mismatch in section " + section_name(id) + ": the file is damaged (voxlines verify checks all)");
  checked.store(1, std::memory_order_release);
}

const SectionEntry* VxlFile::find_section(std::uint32_t id) const {
  for (const SectionEntry& e : sections_) {
    std::uint32_t eid;
    std::memcpy(&eid, e.id, 4);
    if (eid == id) return &e;
  }
  return nullptr;
}

std::uint64_t VxlFile::provenance_offset() const {
  const SectionEntry* s = find_section(section_id("PROV"));
  return s ? s->offset : 0;
}

OrderView VxlFile::order(std::size_t voxel, std::uint32_t k, std::uint32_t level) const {
  const VoxelEntry& v = voxels_[voxel];
  const LevelEntry counts = this->level(voxel, level);
  OrderView o;
  o.bits = order_entry_bits(counts.vertex_count, order_packing_);
  o.count = counts.segment_count;
  o.data = orders_.data() + level_orders_offset(v, levels_of(voxel), level, meta_.stored_order_count, order_packing_) +
           k * order_array_bytes(counts.segment_count, o.bits);
  return o;
}

std::uint64_t VxlFile::orders_offset() const {
  return find_section(section_id(order_packing_ == OrderPacking::Bits ? "ORDB" : "ORDR"))->offset;
}

void VxlFile::read_vertices(std::size_t voxel, std::uint64_t first, std::uint64_t count, float* xyz) const {
  if (position_encoding() == PositionEncoding::Packed)
    unpack_block(voxels_[voxel], packed_vertices_.data() + first, count, xyz);
  else
    std::copy_n(float_vertices_.data() + 3 * first, 3 * count, xyz);
}

std::vector<float> VxlFile::all_vertices() const {
  std::vector<float> xyz(3 * meta_.vertex_count);
  for (std::size_t i = 0; i < voxels_.size(); ++i)
    read_vertices(i, voxels_[i].vertex_first, voxels_[i].vertex_count, xyz.data() + 3 * voxels_[i].vertex_first);
  return xyz;
}

// The steps of spec §7's `open`, in order; each sets the spans the next relies on.
void VxlFile::validate() {
  validate_header();
  validate_section_table();
  validate_meta_and_sizes();
  validate_voxel_table();
}

namespace {

// What a file that is not a .vxl is, from its first bytes, and what to do with it: a message a user can act
// on; "" when unknown.
std::string other_format_hint(const std::uint8_t* bytes, std::uint64_t size) {
  const char* convert = ", not a .vxl file: convert it first (voxlines convert IN OUT.vxl)";
  const std::string_view start(reinterpret_cast<const char*>(bytes), std::min<std::uint64_t>(size, 64));
  if (start.starts_with("mrtrix tracks")) return std::string("this is an MRtrix TCK file") + convert;
  if (start.starts_with("mrtrix track scalars"))
    return "this is an MRtrix TSF file (values for a TCK), not a .vxl file";
  if (start.starts_with("TRACK")) return std::string("this is a TrackVis TRK file") + convert;
  if (start.starts_with("# vtk DataFile")) return std::string("this is a legacy VTK file") + convert;
  if (start.starts_with("<?xml") || start.starts_with("<VTKFile"))
    return std::string("this is an XML file (a VTK .vtp?)") + convert;
  if (start.starts_with("PK\x03\x04")) return std::string("this is a zip archive (a TRX file?)") + convert;
  if (start.starts_with("\x1f\x8b")) return std::string("this is a gzip file (a .trk.gz?)") + convert;
  if (size >= 8 && std::memcmp(bytes, kVxlzMagic.data(), 8) == 0)
    return "this is a .vxlz package, not a .vxl file: voxlines unpack IN.vxlz OUT.vxl makes the .vxl";
  return "";
}

}  // namespace

// §7 step 1.
void VxlFile::validate_header() {
  const std::string& p = file_.path();
  const std::uint64_t size = file_size_;
  const std::uint8_t* base = file_.data();
  if (const std::string hint = other_format_hint(base, file_.size()); !hint.empty()) fail_input(p, 0, hint);
  if (size < sizeof(FileHeader)) fail_input(p, size, "file too short for a .vxl header (64 bytes)");
  if (file_.size() < sizeof(FileHeader)) fail_input(p, file_.size(), "the first bytes read end before the header");
  std::memcpy(&header_, base, sizeof header_);
  if (std::memcmp(header_.magic, kVxlMagic.data(), 8) != 0) fail_input(p, 0, "not a .vxl file (bad magic)");
  if (header_.version_major != kVxlVersionMajor && header_.version_major != kVxlVersionMajorPackedPositions)
    throw Error(ErrorKind::Unsupported, p, 8,
                ".vxl major version " + std::to_string(header_.version_major) + " (this reader knows 1 and 2)");
  if (header_.header_size != sizeof(FileHeader)) fail_input(p, 12, "header_size must be 64");
  if (header_.file_size != size)
    fail_input(p, 16,
               "file size is " + std::to_string(size) + " bytes but the header says " +
                   std::to_string(header_.file_size) + " (truncated or extended file)");
  if (header_.section_table_offset != sizeof(FileHeader)) fail_input(p, 24, "section table must start at byte 64");
  if (header_.section_count == 0 || header_.section_count > kVxlMaxSections)
    fail_input(p, 32, "section count must be 1..64");
  if (header_.flags != 0) fail_input(p, 36, "unknown header flags");
  const std::uint64_t table_end = sizeof(FileHeader) + std::uint64_t(header_.section_count) * sizeof(SectionEntry);
  if (table_end > size) fail_input(p, 64, "section table runs past the end of the file");
  if (table_end > file_.size())
    fail_input(p, file_.size(),
               "the first bytes read end before the section table (" + std::to_string(table_end) + " bytes)");
  sections_ = {reinterpret_cast<const SectionEntry*>(base + sizeof(FileHeader)), header_.section_count};
}

// §7 step 2: every entry in bounds, aligned, in order, unique; unknown required sections refused.
void VxlFile::validate_section_table() {
  const std::string& p = file_.path();
  const std::uint64_t size = file_size_;
  const std::uint64_t table_end = sizeof(FileHeader) + sections_.size_bytes();
  std::uint64_t previous_end = table_end;
  std::vector<std::uint32_t> seen;
  for (std::size_t i = 0; i < sections_.size(); ++i) {
    const SectionEntry& e = sections_[i];
    const std::uint64_t at = sizeof(FileHeader) + i * sizeof(SectionEntry);
    std::uint32_t id;
    std::memcpy(&id, e.id, 4);
    const std::string name = section_name(id);
    for (int k = 0; k < 4; ++k)
      if (static_cast<unsigned char>(e.id[k]) < 0x20 || static_cast<unsigned char>(e.id[k]) > 0x7E)
        fail_input(p, at + k, "section id '" + name + "' is not four printable ASCII characters");
    if (e.offset % kVxlAlignment != 0) fail_input(p, at + 8, "section " + name + " offset is not a multiple of 64");
    if (e.offset < previous_end)
      fail_input(p, at + 8, "section " + name + " overlaps the table or the previous section");
    if (e.offset > size || e.size > size - e.offset)
      fail_input(p, at + 16, "section " + name + " runs past the end of the file");
    if ((e.flags & ~kSectionRequired) != 0) fail_input(p, at + 4, "section " + name + " has unknown flags");
    if (std::find(seen.begin(), seen.end(), id) != seen.end()) fail_input(p, at, "section " + name + " appears twice");
    seen.push_back(id);
    previous_end = e.offset + e.size;
    // The sections a reader must understand to draw the file right (spec §4): they carry the required flag,
    // or an older reader that skipped them (LODS, VDIR) would draw garbage without a word.
    static const std::uint32_t required[] = {
        section_id("META"), section_id("DIRS"), section_id("VOXT"), section_id("LODS"), section_id("VERT"),
        section_id("ORDR"), section_id("ORDB"), section_id("VXLN"), section_id("STRM"), section_id("VDIR")};
    static const std::uint32_t optional[] = {section_id("PROV"), section_id("GRPS"), section_id("VVAL"),
                                             section_id("SVAL"), section_id("GDAT"), section_id("VXIX"),
                                             section_id("SLEN")};
    const bool is_required = std::find(std::begin(required), std::end(required), id) != std::end(required);
    const bool is_optional = std::find(std::begin(optional), std::end(optional), id) != std::end(optional);
    if (is_required && !(e.flags & kSectionRequired))
      fail_input(p, at + 4, "section " + name + " must carry the required flag (spec §4)");
    if (!is_required && !is_optional && (e.flags & kSectionRequired))
      throw Error(ErrorKind::Unsupported, p, at,
                  "required section " + name + " is unknown to this reader (newer writer?)");
  }
}

// §7 step 3, META's own fields (meta_ read from the file's META at `meta_at`).
void VxlFile::validate_meta_fields(std::uint64_t meta_at) const {
  const std::string& p = file_.path();
  const MetaSection& m = meta_;
  if (!std::isfinite(m.voxel_size) || !(m.voxel_size > 0))
    fail_input(p, meta_at + 56, "voxel size must be finite and positive");
  if (m.stored_order_count < 1 || m.stored_order_count > kVxlMaxStoredOrders)
    fail_input(p, meta_at + 52, "stored order count must be 1..64");
  if (m.voxel_count > std::uint32_t(std::numeric_limits<std::int32_t>::max()))
    fail_input(p, meta_at + 48, "voxel count exceeds 2^31-1");
  for (int c = 0; c < 3; ++c) {
    if (m.grid_dims[c] < 0) fail_input(p, meta_at + 88 + 4 * c, "negative grid dimension");
    if (!std::isfinite(m.grid_origin[c]) || !std::isfinite(m.bounds_min[c]) || !std::isfinite(m.bounds_max[c]))
      fail_input(p, meta_at + 64, "non-finite grid origin or bounds");
  }
  check_grid_geometry(m, p, meta_at);
  // Every source point and every synthetic one is a vertex (spec §6.2), so these bound what a reader
  // reserves for the points: an unchecked point_count would ask for up to 2^64 floats.
  if (m.point_count > m.vertex_count || m.synthetic_point_count > m.vertex_count - m.point_count)
    fail_input(p, meta_at + 8,
               "point_count " + std::to_string(m.point_count) + " + synthetic_point_count " +
                   std::to_string(m.synthetic_point_count) + " exceed vertex_count " + std::to_string(m.vertex_count));
}

// §7 step 3: META, and every section's size against its counts; sets the section spans.
void VxlFile::validate_meta_and_sizes() {
  const std::string& p = file_.path();
  const std::uint8_t* base = file_.data();
  auto section = [&](const char(&id)[5], bool required) -> std::span<const std::uint8_t> {
    const SectionEntry* e = find_section(section_id(id));
    if (!e) {
      if (required) fail_input(p, 64, std::string("required section ") + id + " is missing");
      return {};
    }
    return {base + e->offset, static_cast<std::size_t>(e->size)};
  };
  auto offset_of = [&](const char(&id)[5]) -> std::uint64_t { return find_section(section_id(id))->offset; };

  // META and counts (§7 step 3).
  auto meta = section("META", true);
  if (meta.size() != sizeof(MetaSection)) fail_input(p, offset_of("META"), "META must be 256 bytes");
  std::memcpy(&meta_, meta.data(), sizeof meta_);
  const std::uint64_t meta_at = offset_of("META");
  const MetaSection& m = meta_;
  validate_meta_fields(meta_at);
  auto expect_size = [&](const char(&id)[5], std::optional<std::uint64_t> expected, const char* what) {
    auto s = section(id, true);
    if (!expected || s.size() != *expected)
      fail_input(p, offset_of(id),
                 std::string("section ") + id + " size " + std::to_string(s.size()) + " does not match " + what);
    return s;
  };
  auto dirs =
      expect_size("DIRS", count_product(m.stored_order_count, sizeof(DirectionEntry)), "stored_order_count × 16");
  check_order_set(m, p, meta_at);
  auto voxt = expect_size("VOXT", count_product(m.voxel_count, sizeof(VoxelEntry)), "voxel_count × 64");
  // Positions (spec §5.4): float32 in every 1.x file, either encoding in 2.0.
  const bool packed = m.position_encoding == static_cast<std::uint32_t>(PositionEncoding::Packed);
  if (m.position_encoding > static_cast<std::uint32_t>(PositionEncoding::Packed))
    fail_input(p, meta_at + 152, "unknown position encoding " + std::to_string(m.position_encoding));
  if (packed && header_.version_major < kVxlVersionMajorPackedPositions)
    fail_input(p, meta_at + 152, "packed positions in a version 1 file (they need version 2.0)");
  auto vert = packed ? expect_size("VERT", count_product(m.vertex_count, 4), "vertex_count × 4 (packed positions)")
                     : expect_size("VERT", count_product(m.vertex_count, 12), "vertex_count × 12");
  // Levels of detail (spec §5.12): LODS exactly when level_count > 1, which needs version 2.1.
  const bool has_levels = find_section(section_id("LODS")) != nullptr;
  if (m.level_count == 1 || m.level_count > kMaxLevels)
    fail_input(p, meta_at + 156,
               "level count " + std::to_string(m.level_count) + " must be 0 or 2.." + std::to_string(kMaxLevels));
  if (has_levels != (m.level_count > 1))
    fail_input(p, meta_at + 156,
               has_levels ? "LODS section without a level count" : "level count without a LODS section");
  if (has_levels &&
      (header_.version_major < kVxlVersionMajorPackedPositions ||
       (header_.version_major == kVxlVersionMajorPackedPositions && header_.version_minor < kVxlVersionMinorLevels)))
    fail_input(p, meta_at + 156, "levels of detail in a file before version 2.1");
  if (has_levels) {
    auto lods = expect_size("LODS", count_product(m.voxel_count, std::uint64_t(m.level_count - 1) * sizeof(LevelEntry)),
                            "voxel_count × (level_count − 1) × 8");
    levels_ = {reinterpret_cast<const LevelEntry*>(lods.data()), lods.size() / sizeof(LevelEntry)};
  }
  auto vxln = expect_size("VXLN", count_product(m.voxline_count, sizeof(VoxlineEntry)), "voxline_count × 8");
  std::optional<std::uint64_t> strm_size = m.streamline_count == std::numeric_limits<std::uint64_t>::max()
                                               ? std::nullopt
                                               : count_product(m.streamline_count + 1, 8);
  auto strm = expect_size("STRM", strm_size, "(streamline_count + 1) × 8");
  // The orders: ORDB (bit-packed) since 1.4 / 2.3, ORDR before; exactly one of them (§5.5).
  const bool bit_orders = find_section(section_id("ORDB")) != nullptr;
  if (bit_orders == (find_section(section_id("ORDR")) != nullptr))
    fail_input(p, 64,
               bit_orders ? "both ORDR and ORDB sections: a file holds one of them"
                          : "required section ORDB (or ORDR) is missing");
  order_packing_ = bit_orders ? OrderPacking::Bits : OrderPacking::Bytes;
  orders_ = section(bit_orders ? "ORDB" : "ORDR", true);
  validate_voxel_index(section("VXIX", false));
  if (find_section(section_id("SLEN")) != nullptr) {
    auto slen = expect_size("SLEN", count_product(m.streamline_count, sizeof(float)), "streamline_count × 4");
    streamline_lengths_ = {reinterpret_cast<const float*>(slen.data()), slen.size() / sizeof(float)};
  }
  // Per-voxel directions: present exactly when the order set is random (§5.10).
  const bool random_set = m.order_set == static_cast<std::uint32_t>(OrderSet::Random);
  if (random_set != (find_section(section_id("VDIR")) != nullptr))
    fail_input(p, meta_at + 100,
               random_set ? "order set random needs a VDIR section" : "VDIR section without order set random");
  if (random_set) {
    auto vdir = expect_size("VDIR", count_product(m.voxel_count, dirs.size()), "voxel_count × stored_order_count × 16");
    voxel_directions_ = {reinterpret_cast<const DirectionEntry*>(vdir.data()), vdir.size() / sizeof(DirectionEntry)};
  }
  directions_ = {reinterpret_cast<const DirectionEntry*>(dirs.data()), m.stored_order_count};
  voxels_ = {reinterpret_cast<const VoxelEntry*>(voxt.data()), m.voxel_count};
  if (packed)
    packed_vertices_ = {reinterpret_cast<const std::uint32_t*>(vert.data()), static_cast<std::size_t>(m.vertex_count)};
  else
    float_vertices_ = {reinterpret_cast<const float*>(vert.data()), static_cast<std::size_t>(m.vertex_count * 3)};
  voxlines_ = {reinterpret_cast<const VoxlineEntry*>(vxln.data()), static_cast<std::size_t>(m.voxline_count)};
  strm_ = {reinterpret_cast<const std::uint64_t*>(strm.data()), static_cast<std::size_t>(m.streamline_count + 1)};
  auto prov = section("PROV", false);
  provenance_ = {reinterpret_cast<const char*>(prov.data()), prov.size()};
  groups_ = section("GRPS", false);
  std::uint64_t group_count = 0;
  walk_groups([&](std::string_view, std::uint64_t, std::uint64_t) { ++group_count; });  // O(groups)
  if (find_section(section_id("GDAT"))) {
    // Small (one row per group and name): parsed and checked whole, O(its bytes).
    const std::uint64_t at0 = offset_of("GDAT");
    group_values_ =
        decode_group_values(section("GDAT", false), group_count,
                            [&](std::uint64_t pos, const std::string& what) { fail_input(p, at0 + pos, what); });
  }
  if (find_section(section_id("VVAL")))
    vertex_values_ = ValueSets(section("VVAL", true), m.vertex_count, p, offset_of("VVAL"));
  if (find_section(section_id("SVAL")))
    streamline_values_ = ValueSets(section("SVAL", true), m.streamline_count, p, offset_of("SVAL"));
}

// §7 step 4: every voxel's coordinates, flags, vertex and order ranges (and tight bounds, when packed
// positions are decoded from them). O(voxels).
bool tight_bounds_in_place(const MetaSection& m, const VoxelEntry& v, int c) {
  const double cell_lo = m.grid_origin[c] + double(v.coord[c]) * m.voxel_size;
  const double lo = std::max(cell_lo - 1.5 * m.voxel_size, m.bounds_min[c] - m.voxel_size);
  const double hi = std::min(cell_lo + 2.5 * m.voxel_size, m.bounds_max[c] + m.voxel_size);
  return v.tight_min[c] >= lo && v.tight_max[c] <= hi;
}

std::string misplaced_voxel(const MetaSection& m, const VoxelEntry& v, std::size_t index, int c) {
  const double cell_lo = m.grid_origin[c] + double(v.coord[c]) * m.voxel_size;
  return "voxel " + std::to_string(index) + " tight bounds on " + std::string(1, "xyz"[c]) +
         " lie outside its cell and the file's bounds (" + std::to_string(v.tight_min[c]) + " .. " +
         std::to_string(v.tight_max[c]) + " mm, the cell's " + std::to_string(cell_lo) + " .. " +
         std::to_string(cell_lo + m.voxel_size) + " mm)";
}

void check_levels_nested(const VoxelEntry& v, std::span<const LevelEntry> row, std::size_t index,
                         const std::string& path, std::uint64_t lods_at) {
  for (std::uint32_t d = 0; d < row.size(); ++d) {
    const LevelEntry finer = voxel_level(v, row, d), e = row[d];
    if (e.vertex_count > finer.vertex_count || e.segment_count > finer.segment_count ||
        (e.vertex_count > 0 ? e.segment_count >= e.vertex_count : e.segment_count != 0))
      fail_input(path, lods_at + (index * row.size() + d) * sizeof(LevelEntry),
                 "voxel " + std::to_string(index) + " level " + std::to_string(d + 1) + " is not a prefix of level " +
                     std::to_string(d) + " with fewer segments than vertices");
  }
}

void check_order_set(const MetaSection& m, const std::string& p, std::uint64_t meta_at) {
  if (m.order_set > static_cast<std::uint32_t>(OrderSet::Random))
    fail_input(p, meta_at + 100, "unknown order set " + std::to_string(m.order_set) + " (expected 0, 1 or 2)");
  const std::uint32_t fixed_count = m.order_set == static_cast<std::uint32_t>(OrderSet::Axis)       ? 3
                                    : m.order_set == static_cast<std::uint32_t>(OrderSet::AxisDiag) ? 7
                                                                                                    : 0;
  if (fixed_count != 0 && m.stored_order_count != fixed_count)
    fail_input(p, meta_at + 52,
               "stored order count " + std::to_string(m.stored_order_count) + " for order set " +
                   std::to_string(m.order_set) + " (it stores " + std::to_string(fixed_count) + ")");
}

void check_grid_geometry(const MetaSection& m, const std::string& p, std::optional<std::uint64_t> meta_at) {
  const double s = m.voxel_size;
  auto at = [&](std::uint64_t field) {
    return meta_at ? std::optional<std::uint64_t>(*meta_at + field) : std::nullopt;
  };
  for (int c = 0; c < 3; ++c) {
    const std::string axis = std::string(1, "xyz"[c]);
    if (!(m.bounds_min[c] <= m.bounds_max[c])) fail_input(p, at(104 + 8 * c), "bounds_min above bounds_max on " + axis);
    if (!(std::abs(m.grid_origin[c] - m.bounds_min[c]) <= s))
      fail_input(p, at(64 + 8 * c), "grid origin is not at bounds_min on " + axis);
    const double cells = std::floor((m.bounds_max[c] - m.bounds_min[c]) / s) + 1;
    if (!(std::abs(double(m.grid_dims[c]) - cells) <= 1))
      fail_input(p, at(88 + 4 * c),
                 "grid_dims on " + axis + " is " + std::to_string(m.grid_dims[c]) +
                     "; the bounds and voxel size make " +
                     std::to_string(static_cast<std::uint64_t>(std::min(cells, 1e19))) + " cells");
  }
}

// VXIX (§5.14), O(voxels): its size from the counts, and voxel lists that start at 0, never shrink and end at
// the voxline count, so that a list never reads past the entries. The entries themselves are checked by
// their users (streamline below the count, voxlines within the block), as VXLN's are.
void VxlFile::validate_voxel_index(std::span<const std::uint8_t> vxix) {
  if (vxix.data() == nullptr) return;
  const std::string& p = file_.path();
  const std::uint64_t at = find_section(section_id("VXIX"))->offset;
  const std::optional<std::uint64_t> lists = count_product(meta_.voxline_count, sizeof(IndexedVoxline));
  const std::optional<std::uint64_t> expected = lists ? count_sum(8 * (meta_.voxel_count + 1ull), *lists) : lists;
  if (!expected || vxix.size() != *expected)
    fail_input(p, at,
               "section VXIX size " + std::to_string(vxix.size()) +
                   " does not match (voxel_count + 1) × 8 + voxline_count × 4");
  if (meta_.streamline_count > IndexedVoxline::kStreamlineMask + 1ull)
    fail_input(p, at, "section VXIX in a file of more than 2^29 streamlines (its entries number them in 29 bits)");
  const auto* first = reinterpret_cast<const std::uint64_t*>(vxix.data());
  for (std::uint64_t i = 0; i <= meta_.voxel_count; ++i)
    if ((i == 0 && first[0] != 0) || (i > 0 && first[i] < first[i - 1]) ||
        (i == meta_.voxel_count && first[i] != meta_.voxline_count))
      fail_input(p, at + 8 * i, "VXIX voxel list starts must rise from 0 to the voxline count");
  voxel_index_first_ = {first, static_cast<std::size_t>(meta_.voxel_count + 1)};
  voxel_index_entries_ = {reinterpret_cast<const IndexedVoxline*>(first + meta_.voxel_count + 1),
                          static_cast<std::size_t>(meta_.voxline_count)};
}

void VxlFile::validate_voxel_table() {
  const std::string& p = file_.path();
  const MetaSection& m = meta_;
  const bool packed = position_encoding() == PositionEncoding::Packed;
  const std::uint64_t voxt_at = find_section(section_id("VOXT"))->offset;
  const std::uint64_t lods_at = levels_.empty() ? 0 : find_section(section_id("LODS"))->offset;
  std::uint64_t next_vertex = 0, segments = 0, min_order_offset = 0;
  for (std::size_t i = 0; i < voxels_.size(); ++i) {
    const VoxelEntry& v = voxels_[i];
    const std::uint64_t at = voxt_at + i * sizeof(VoxelEntry);
    for (int c = 0; c < 3; ++c)
      if (v.coord[c] < 0 || v.coord[c] >= m.grid_dims[c]) fail_input(p, at, "voxel coordinate outside the grid");
    if (i > 0) {
      const VoxelEntry& u = voxels_[i - 1];
      auto key = [](const VoxelEntry& e) { return std::array<std::int32_t, 3>{e.coord[2], e.coord[1], e.coord[0]}; };
      if (!(key(u) < key(v))) fail_input(p, at, "voxel coordinates not strictly increasing in (z, y, x)");
    }
    if (v.flags != order_width_code(v.vertex_count))
      fail_input(p, at + 12, "voxel flags must hold the order width code for its vertex count");
    if (v.vertex_count < 1) fail_input(p, at + 48, "voxel with no vertices");
    if (v.segment_count >= v.vertex_count) fail_input(p, at + 52, "voxel has as many segments as vertices");
    // Packed positions are decoded from the tight bounds: they must give finite values (spec §5.4).
    if (packed)
      for (int c = 0; c < 3; ++c)
        if (!std::isfinite(v.tight_min[c]) || !std::isfinite(v.tight_max[c]) || !(v.tight_min[c] <= v.tight_max[c]) ||
            !std::isfinite(v.tight_max[c] - v.tight_min[c]))
          fail_input(p, at + 16 + 4 * c,
                     "voxel " + std::to_string(i) + " tight bounds are not finite and ordered (packed positions)");
    for (int c = 0; c < 3; ++c)
      if (!tight_bounds_in_place(m, v, c)) fail_input(p, at + 16 + 4 * c, misplaced_voxel(m, v, i, c));
    if (v.vertex_first != next_vertex) fail_input(p, at + 40, "voxel vertex blocks are not contiguous");
    next_vertex += v.vertex_count;
    if (next_vertex > m.vertex_count) fail_input(p, at + 48, "voxel vertex block runs past vertex_count");
    if (v.order_offset % 4 != 0 || v.order_offset < min_order_offset)
      fail_input(p, at + 56, "order offset not a multiple of 4 or decreasing");
    const std::span<const LevelEntry> row = levels_of(i);
    check_levels_nested(v, row, i, p, lods_at);
    std::uint64_t bytes = voxel_all_orders_size(v, row, m.stored_order_count, order_packing_);
    if (v.order_offset > orders_.size() || bytes > orders_.size() - v.order_offset)
      fail_input(p, at + 56,
                 std::string("voxel orders run past the ") + (order_packing_ == OrderPacking::Bits ? "ORDB" : "ORDR") +
                     " section");
    min_order_offset = v.order_offset + bytes;
    segments += v.segment_count;
  }
  if (next_vertex != m.vertex_count) fail_input(p, voxt_at, "voxel blocks do not cover all vertices");
  if (segments != m.segment_count) fail_input(p, voxt_at, "voxel segment counts do not add up to segment_count");
  if (m.voxel_count == 0 && m.vertex_count != 0) fail_input(p, voxt_at, "vertices without voxels");
}

void VxlFile::walk_groups(
    const std::function<void(std::string_view name, std::uint64_t members_at, std::uint64_t count)>& visit) const {
  if (groups_.empty()) return;
  const std::string& p = file_.path();
  const std::uint64_t at0 = find_section(section_id("GRPS"))->offset;
  std::uint64_t pos = 0;
  auto need = [&](std::uint64_t n) {
    if (n > groups_.size() - pos) fail_input(p, at0 + pos, "GRPS section truncated");
  };
  auto take = [&](void* dst, std::uint64_t n) {
    need(n);
    std::memcpy(dst, groups_.data() + pos, n);
    pos += n;
  };
  std::uint32_t header[2];
  take(header, 8);
  for (std::uint32_t g = 0; g < header[0]; ++g) {
    std::uint32_t len;
    take(&len, 4);
    need(len);
    const std::string_view name(reinterpret_cast<const char*>(groups_.data() + pos), len);
    if (name.find('\0') != std::string_view::npos) fail_input(p, at0 + pos, "GRPS group name contains a NUL byte");
    if (!is_valid_utf8(name)) fail_input(p, at0 + pos, "GRPS group name is not valid UTF-8");
    pos += len;
    std::uint64_t aligned = align_up(pos, 8);
    need(aligned - pos);
    pos = aligned;
    std::uint64_t count;
    take(&count, 8);
    if (count > (groups_.size() - pos) / 8) fail_input(p, at0 + pos, "GRPS member count runs past the section");
    visit(name, pos, count);
    pos += count * 8;
  }
}

std::vector<StreamlineGroup> VxlFile::groups() const {
  std::vector<StreamlineGroup> out;
  const std::string& p = file_.path();
  const std::uint64_t at0 = groups_.empty() ? 0 : find_section(section_id("GRPS"))->offset;
  walk_groups([&](std::string_view name, std::uint64_t members_at, std::uint64_t count) {
    StreamlineGroup gc;
    gc.name = name;
    gc.members.resize(count);
    if (count > 0) std::memcpy(gc.members.data(), groups_.data() + members_at, count * 8);
    for (std::uint64_t i = 0; i < count; ++i)
      if (gc.members[i] >= meta_.streamline_count || (i > 0 && gc.members[i] <= gc.members[i - 1]))
        fail_input(p, at0 + members_at + 8 * i, "GRPS member out of range or not increasing");
    out.push_back(std::move(gc));
  });
  return out;
}

void VxlFile::check_streamline_table() const {
  for (std::uint64_t s = 0; s + 1 < strm_.size(); ++s) check_streamline_run(s);
  if (strm_.back() != voxlines_.size()) fail_streamline_table(strm_.size() - 1);
}

void VxlFile::fail_streamline_table(std::uint64_t entry) const {
  const std::uint64_t at = find_section(section_id("STRM"))->offset + 8 * entry;
  if (entry == 0) fail_input(path(), at, "streamline table must start at voxline 0");
  if (strm_[entry] < strm_[entry - 1]) fail_input(path(), at, "streamline table not non-decreasing");
  if (strm_[entry] > voxlines_.size()) fail_input(path(), at, "streamline table points past the voxline table");
  fail_input(path(), at, "streamline table must end at voxline_count");
}

void VxlFile::fail_voxline(std::uint64_t j) const {
  const std::uint64_t at = find_section(section_id("VXLN"))->offset + 8 * j;
  if (voxlines_[j].voxel >= voxels_.size()) fail_input(path(), at, "voxline refers to a voxel past the table");
  fail_input(path(), at, "voxline with no points");
}

}  // namespace vxl
