#include "format/vxl_level_image.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>
#include <new>
#include <optional>
#include <stdexcept>

#include "format/base/checksum.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_levels.h"
#include "format/vxl_positions.h"
#include "format/vxl_sections.h"

namespace vxl {
namespace {

std::uint32_t id_of(const SectionEntry& e) {
  std::uint32_t id;
  std::memcpy(&id, e.id, 4);
  return id;
}

// The sections make_level_image reads whole; the others it places or leaves out.
bool read_whole(std::uint32_t id) {
  static const std::uint32_t whole[] = {section_id("META"), section_id("DIRS"), section_id("VDIR"),
                                        section_id("VOXT"), section_id("LODS"), section_id("PROV")};
  return std::find(std::begin(whole), std::end(whole), id) != std::end(whole);
}

// What make_level_image reads of a file with these sections (ranges_for_level_image).
std::vector<ByteRange> table_ranges(const std::vector<SectionEntry>& sections) {
  std::vector<ByteRange> ranges{{0, sizeof(FileHeader) + sections.size() * sizeof(SectionEntry)}};
  for (const SectionEntry& e : sections)
    if (read_whole(id_of(e))) ranges.push_back({e.offset, e.offset + e.size});
  return merge_ranges(std::move(ranges), 0);
}

// Enough of the gathered tables for the header and the section table (they come first).
std::span<const std::uint8_t> head_of(std::span<const std::uint8_t> gathered) {
  return gathered.first(std::min<std::size_t>(gathered.size(), kSectionTableBytesMax));
}

// The file's tables, from the bytes of ranges_for_level_image one after another, each checked against its checksum.
class GatheredTables {
 public:
  GatheredTables(const std::string& path, std::span<const std::uint8_t> gathered, std::uint64_t file_size)
      : path_(path),
        sections_(VxlFile::read_section_table(path, head_of(gathered), file_size)),
        ranges_(table_ranges(sections_)),
        gathered_(gathered) {
    std::uint64_t total = 0;
    for (const ByteRange& r : ranges_) total += r.end - r.begin;
    if (total != gathered.size())
      throw Error(ErrorKind::Input, path, std::nullopt,
                  "the tables read for a level image are " + std::to_string(gathered.size()) + " bytes, not " +
                      std::to_string(total));
    check_header_checksum();
  }
  const std::string& path() const { return path_; }
  const SectionEntry* find(const char (&id)[5]) const {
    for (const SectionEntry& e : sections_)
      if (id_of(e) == section_id(id)) return &e;
    return nullptr;
  }
  const SectionEntry& require(const char (&id)[5]) const {
    const SectionEntry* e = find(id);
    if (!e) fail_input(path_, 64, std::string("required section ") + id + " is missing");
    return *e;
  }
  // A section read whole, checked against its checksum; empty when the file has none.
  std::span<const std::uint8_t> section(const char (&id)[5]) const {
    const SectionEntry* e = find(id);
    if (!e || e->size == 0) return {};
    std::uint64_t at = 0;
    for (const ByteRange& r : ranges_) {
      if (r.begin <= e->offset && e->offset + e->size <= r.end) {
        const std::span<const std::uint8_t> bytes = gathered_.subspan(at + (e->offset - r.begin), e->size);
        if (xxh3_64(bytes.data(), bytes.size()) != e->checksum)
          fail_input(path_, e->offset, std::string("checksum mismatch in section ") + id + ": the file is damaged");
        return bytes;
      }
      at += r.end - r.begin;
    }
    fail_input(path_, e->offset, std::string("section ") + id + " was not read");
  }

 private:
  void check_header_checksum() const {
    const std::uint64_t table_end = sizeof(FileHeader) + sections_.size() * sizeof(SectionEntry);
    std::vector<std::uint8_t> head(gathered_.begin(), gathered_.begin() + static_cast<std::ptrdiff_t>(table_end));
    FileHeader h;
    std::memcpy(&h, head.data(), sizeof h);
    std::memset(head.data() + offsetof(FileHeader, header_checksum), 0, 8);
    if (xxh3_64(head.data(), head.size()) != h.header_checksum)
      fail_input(path_, 40, "header checksum mismatch (header or section table damaged)");
  }

  std::string path_;
  std::vector<SectionEntry> sections_;
  std::vector<ByteRange> ranges_;
  std::span<const std::uint8_t> gathered_;
};

// The file's voxel table and levels, checked for what placing them relies on: each level a prefix of the finer one,
// the vertex blocks contiguous within VERT, the orders in order within their section.
struct FileVoxels {
  MetaSection meta{};
  std::span<const VoxelEntry> voxels;
  std::span<const LevelEntry> levels;  // voxel_count x (level_count - 1)
  std::uint32_t level_count = 1;
  OrderPacking packing = OrderPacking::Bits;
  std::uint64_t vertex_word = 4;
  const SectionEntry* vert = nullptr;
  const SectionEntry* orders = nullptr;

  std::span<const LevelEntry> row(std::size_t i) const {
    return levels.subspan(i * (level_count - 1), level_count - 1);
  }
};

void check_voxel_runs(const GatheredTables& t, const FileVoxels& f) {
  const std::uint64_t voxt_at = t.require("VOXT").offset;
  std::uint64_t next_vertex = 0, min_order_offset = 0;
  for (std::size_t i = 0; i < f.voxels.size(); ++i) {
    const VoxelEntry& v = f.voxels[i];
    const std::uint64_t at = voxt_at + i * sizeof(VoxelEntry);
    if (v.vertex_first != next_vertex) fail_input(t.path(), at + 40, "voxel vertex blocks are not contiguous");
    next_vertex += v.vertex_count;
    if (next_vertex > f.meta.vertex_count) fail_input(t.path(), at + 48, "voxel vertex block runs past vertex_count");
    const std::span<const LevelEntry> row = f.row(i);
    if (!row.empty()) check_levels_nested(v, row, i, t.path(), t.require("LODS").offset);
    const std::uint64_t bytes = voxel_all_orders_size(v, row, f.meta.stored_order_count, f.packing);
    if (v.order_offset % 4 != 0 || v.order_offset < min_order_offset || v.order_offset > f.orders->size ||
        bytes > f.orders->size - v.order_offset)
      fail_input(t.path(), at + 56, "voxel orders are not in order within their section");
    min_order_offset = v.order_offset + bytes;
  }
}

FileVoxels read_file_voxels(const GatheredTables& t) {
  FileVoxels f;
  const std::string& p = t.path();
  const std::span<const std::uint8_t> meta = t.section("META");
  const std::uint64_t meta_at = t.require("META").offset;
  if (meta.size() != sizeof(MetaSection)) fail_input(p, meta_at, "META must be 256 bytes");
  std::memcpy(&f.meta, meta.data(), sizeof f.meta);
  const MetaSection& m = f.meta;
  if (m.stored_order_count < 1 || m.stored_order_count > kVxlMaxStoredOrders)
    fail_input(p, meta_at + 52, "stored order count must be 1..64");
  if (m.position_encoding > static_cast<std::uint32_t>(PositionEncoding::Packed))
    fail_input(p, meta_at + 152, "unknown position encoding " + std::to_string(m.position_encoding));
  if (m.level_count == 1 || m.level_count > kMaxLevels)
    fail_input(p, meta_at + 156,
               "level count " + std::to_string(m.level_count) + " must be 0 or 2.." + std::to_string(kMaxLevels));
  f.level_count = std::max<std::uint32_t>(1, m.level_count);
  if (t.section("DIRS").size() != std::uint64_t(m.stored_order_count) * sizeof(DirectionEntry))
    fail_input(p, t.require("DIRS").offset, "section DIRS size does not match stored_order_count × 16");
  // Per-voxel directions exactly with the random order set (spec §5.10), as VxlFile::open requires.
  if ((m.order_set == static_cast<std::uint32_t>(OrderSet::Random)) != (t.find("VDIR") != nullptr))
    fail_input(p, meta_at + 100, "a VDIR section exactly when the order set is random");
  if (t.find("VDIR") &&
      t.section("VDIR").size() != std::uint64_t(m.voxel_count) * m.stored_order_count * sizeof(DirectionEntry))
    fail_input(p, t.require("VDIR").offset, "section VDIR size does not match voxel_count × stored_order_count × 16");
  const std::span<const std::uint8_t> voxt = t.section("VOXT");
  if (voxt.size() != std::uint64_t(m.voxel_count) * sizeof(VoxelEntry))
    fail_input(p, t.require("VOXT").offset, "section VOXT size does not match voxel_count × 64");
  f.voxels = {reinterpret_cast<const VoxelEntry*>(voxt.data()), m.voxel_count};
  const std::span<const std::uint8_t> lods = t.section("LODS");
  const std::uint64_t per_voxel = std::uint64_t(f.level_count - 1) * sizeof(LevelEntry);
  if (lods.size() != std::uint64_t(m.voxel_count) * per_voxel || (f.level_count > 1) != (t.find("LODS") != nullptr))
    fail_input(p, meta_at + 156, "section LODS does not match the level count");
  f.levels = {reinterpret_cast<const LevelEntry*>(lods.data()), lods.size() / sizeof(LevelEntry)};
  f.vertex_word = vertex_bytes(static_cast<PositionEncoding>(m.position_encoding));
  f.vert = &t.require("VERT");
  if (f.vert->size / f.vertex_word != m.vertex_count || f.vert->size % f.vertex_word != 0)
    fail_input(p, f.vert->offset, "section VERT size does not match vertex_count");
  f.orders = t.find("ORDB");
  if (!f.orders) {
    f.orders = &t.require("ORDR");
    f.packing = OrderPacking::Bytes;
  }
  if (f.orders->offset < f.vert->offset)
    throw Error(ErrorKind::Unsupported, p, f.orders->offset,
                "orders before the vertices: not a layout any writer makes");
  check_voxel_runs(t, f);
  return f;
}

// What the image of level `level` holds: its META (the counts of that level), its order bytes, its layout.
struct ImagePlan {
  MetaSection meta{};
  std::uint64_t order_bytes = 0;
  VxlLayout layout;
};

ImagePlan plan_image(const FileVoxels& f, std::uint32_t level, std::uint64_t provenance_bytes) {
  ImagePlan plan;
  MetaSection& m = plan.meta;
  m = f.meta;
  m.vertex_count = m.segment_count = 0;
  m.voxel_count = 0;
  for (std::size_t i = 0; i < f.voxels.size(); ++i) {
    const std::span<const LevelEntry> row = f.row(i);
    const LevelEntry e = voxel_level(f.voxels[i], row, level);
    if (e.vertex_count == 0) continue;
    ++m.voxel_count;
    m.vertex_count += e.vertex_count;
    m.segment_count += e.segment_count;
    for (std::uint32_t d = level; d < f.level_count; ++d)
      plan.order_bytes += level_orders_size(voxel_level(f.voxels[i], row, d), m.stored_order_count, f.packing);
  }
  // Nothing per streamline in the image; its vertices count as its points (a reader frames the lines of a file that
  // has points).
  m.streamline_count = m.voxline_count = m.synthetic_point_count = 0;
  m.point_count = m.vertex_count;
  m.level_count = f.level_count - level > 1 ? f.level_count - level : 0;
  VxlSectionSizes sizes = section_sizes(m, plan.order_bytes, provenance_bytes, 0);
  sizes.voxel_index = sizes.streamline_lengths = 0;
  plan.layout = plan_vxl_layout(sizes);
  if (f.packing == OrderPacking::Bytes)
    for (SectionEntry& e : plan.layout.table)
      if (std::memcmp(e.id, "ORDB", 4) == 0) std::memcpy(e.id, "ORDR", 4);
  return plan;
}

// The finest level whose image takes at most `max_bytes`, and its plan; the coarsest level's plan where none fits.
ImagePlan finest_image_within(const FileVoxels& f, std::uint64_t provenance_bytes, std::uint64_t max_bytes,
                              std::uint32_t& level) {
  level = 0;
  ImagePlan plan = plan_image(f, level, provenance_bytes);
  while (plan.layout.file_size > max_bytes && level + 1 < f.level_count)
    plan = plan_image(f, ++level, provenance_bytes);
  return plan;
}

SectionEntry& entry(VxlLayout& layout, const char (&id)[5]) {
  for (SectionEntry& e : layout.table)
    if (id_of(e) == section_id(id)) return e;
  throw std::logic_error(std::string("no section ") + id + " in the image's layout");
}

// Writes the image's tables into `image` (zeroed) and says where its vertex and order bytes come from.
void write_image(const GatheredTables& t, const FileVoxels& f, std::uint32_t level, ImagePlan& plan,
                 std::uint8_t* image, std::vector<ImagePlacement>& data) {
  const std::uint32_t k = f.meta.stored_order_count;
  const bool random = t.find("VDIR") != nullptr;
  std::vector<VoxelEntry> voxels;
  std::vector<LevelEntry> levels;
  std::vector<std::uint8_t> voxel_directions;
  const std::span<const std::uint8_t> vdir = random ? t.section("VDIR") : std::span<const std::uint8_t>{};
  const std::uint64_t vdir_row = std::uint64_t(k) * sizeof(DirectionEntry);
  const std::uint64_t vert_at = entry(plan.layout, "VERT").offset;
  const std::uint64_t orders_at = entry(plan.layout, f.packing == OrderPacking::Bits ? "ORDB" : "ORDR").offset;
  std::uint64_t next_vertex = 0, next_order = 0;
  std::vector<ImagePlacement> order_runs;
  for (std::size_t i = 0; i < f.voxels.size(); ++i) {
    const VoxelEntry& v = f.voxels[i];
    const std::span<const LevelEntry> row = f.row(i);
    const LevelEntry e = voxel_level(v, row, level);
    if (e.vertex_count == 0) continue;
    VoxelEntry w = v;
    w.vertex_first = next_vertex;
    w.vertex_count = e.vertex_count;
    w.segment_count = e.segment_count;
    w.flags = order_width_code(e.vertex_count);
    w.order_offset = next_order;
    voxels.push_back(w);
    levels.insert(levels.end(), row.begin() + level, row.end());
    if (random)
      voxel_directions.insert(voxel_directions.end(), vdir.begin() + i * vdir_row, vdir.begin() + (i + 1) * vdir_row);
    const std::uint64_t order_bytes = voxel_all_orders_size(v, row, k, f.packing) -
                                      (level_orders_offset(v, row, level, k, f.packing) - v.order_offset);
    data.push_back({f.vert->offset + v.vertex_first * f.vertex_word, e.vertex_count * f.vertex_word,
                    vert_at + next_vertex * f.vertex_word});
    order_runs.push_back(
        {f.orders->offset + level_orders_offset(v, row, level, k, f.packing), order_bytes, orders_at + next_order});
    next_vertex += e.vertex_count;
    next_order += order_bytes;
  }
  data.insert(data.end(), order_runs.begin(), order_runs.end());
  auto put = [&](const char(&id)[5], const void* bytes, std::uint64_t size) {
    SectionEntry& s = entry(plan.layout, id);
    if (size != s.size) throw std::logic_error(std::string("section ") + id + " of the image is not its planned size");
    if (size > 0) std::memcpy(image + s.offset, bytes, size);
    s.checksum = xxh3_64(image + s.offset, s.size);
  };
  put("META", &plan.meta, sizeof plan.meta);
  const std::span<const std::uint8_t> dirs = t.section("DIRS");
  put("DIRS", dirs.data(), dirs.size());
  if (random) put("VDIR", voxel_directions.data(), voxel_directions.size());
  put("VOXT", voxels.data(), voxels.size() * sizeof(VoxelEntry));
  if (plan.meta.level_count > 1) put("LODS", levels.data(), levels.size() * sizeof(LevelEntry));
  const std::uint64_t no_streamlines = 0;
  put("VXLN", nullptr, 0);
  put("STRM", &no_streamlines, sizeof no_streamlines);
  const std::span<const std::uint8_t> provenance = t.section("PROV");
  put("PROV", provenance.data(), provenance.size());
  const std::vector<std::uint8_t> head = vxl_header_bytes(plan.layout.table, plan.layout.file_size,
                                                          static_cast<PositionEncoding>(plan.meta.position_encoding));
  std::memcpy(image, head.data(), head.size());
}

}  // namespace

std::vector<ByteRange> ranges_for_level_image(const std::string& path, std::span<const std::uint8_t> first,
                                              std::uint64_t file_size) {
  return table_ranges(VxlFile::read_section_table(path, first, file_size));
}

LevelImage make_level_image(const std::string& path, std::span<const std::uint8_t> gathered, std::uint64_t file_size,
                            std::uint64_t max_bytes) {
  const GatheredTables tables(path, gathered, file_size);
  const FileVoxels f = read_file_voxels(tables);
  const std::uint64_t provenance_bytes = tables.find("PROV") ? tables.require("PROV").size : 0;
  std::uint32_t level = 0;
  ImagePlan plan = finest_image_within(f, provenance_bytes, max_bytes, level);
  if (plan.layout.file_size > max_bytes || plan.layout.file_size > std::numeric_limits<std::size_t>::max())
    throw Error(ErrorKind::Unsupported, path, std::nullopt,
                "its coarsest level of detail (" + std::to_string(level) + ") takes " +
                    std::to_string(plan.layout.file_size) + " bytes, more than the " + std::to_string(max_bytes) +
                    " this reader holds");
  const SectionEntry& vert = entry(plan.layout, "VERT");
  const SectionEntry& orders = entry(plan.layout, f.packing == OrderPacking::Bits ? "ORDB" : "ORDR");
  const std::vector<ByteRange> to_come{{vert.offset, vert.offset + vert.size},
                                       {orders.offset, orders.offset + orders.size}};
  // Not zeroed where the vertices and orders will come: a page never touched takes no memory (a browser's
  // WebAssembly memory, as a mapping, gets its pages when first written), and the reader fetches only the levels it
  // draws.
  auto* image = static_cast<std::uint8_t*>(
      std::malloc(static_cast<std::size_t>(std::max<std::uint64_t>(1, plan.layout.file_size))));
  if (image == nullptr) throw std::bad_alloc();
  LevelImage out{
      MappedFile::adopt(path, image, static_cast<std::size_t>(plan.layout.file_size)), level, f.meta, {}, {}};
  out.written = ranges_missing(to_come, plan.layout.file_size);
  for (const ByteRange& r : out.written) std::memset(image + r.begin, 0, r.end - r.begin);
  write_image(tables, f, level, plan, image, out.data);
  return out;
}

std::optional<LevelImageSize> level_image_size(const VxlFile& file, std::uint64_t max_bytes) {
  FileVoxels f;
  f.meta = file.meta();
  f.voxels = file.voxels();
  f.level_count = file.level_count();
  if (f.level_count > 1 && !f.voxels.empty())
    f.levels = {file.levels_of(0).data(), f.voxels.size() * (f.level_count - 1)};
  f.packing = file.order_packing();
  std::uint32_t level = 0;
  const ImagePlan plan = finest_image_within(f, file.provenance_json().size(), max_bytes, level);
  if (plan.layout.file_size > max_bytes) return std::nullopt;
  return LevelImageSize{level, plan.layout.file_size};
}

std::vector<ByteRange> source_ranges(std::span<const ImagePlacement> data, std::span<const ByteRange> image_ranges,
                                     std::uint64_t gap) {
  std::vector<ByteRange> out;
  for (const ByteRange& r : image_ranges) {
    auto p = std::partition_point(data.begin(), data.end(),
                                  [&](const ImagePlacement& q) { return q.at + q.size <= r.begin; });
    for (; p != data.end() && p->at < r.end; ++p) {
      const std::uint64_t lo = std::max(r.begin, p->at), hi = std::min(r.end, p->at + p->size);
      if (lo < hi) out.push_back({p->source + (lo - p->at), p->source + (hi - p->at)});
    }
  }
  return merge_ranges(std::move(out), gap);
}

}  // namespace vxl
