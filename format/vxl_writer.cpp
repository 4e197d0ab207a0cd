#include "vxl_writer.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <thread>

#include "checksum.h"

namespace vxl {

std::vector<std::uint8_t> encode_groups(std::span<const GroupContent> groups) {
  std::vector<std::uint8_t> out;
  auto put = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  std::uint32_t header[2] = {static_cast<std::uint32_t>(groups.size()), 0};
  put(header, sizeof header);
  for (const GroupContent& g : groups) {
    std::uint32_t len = static_cast<std::uint32_t>(g.name.size());
    put(&len, 4);
    put(g.name.data(), g.name.size());
    out.resize(align_up(out.size(), 8), 0);
    std::uint64_t count = g.members.size();
    put(&count, 8);
    put(g.members.data(), g.members.size() * 8);
  }
  return out;
}

VxlSectionSizes section_sizes(const MetaSection& m, std::uint64_t order_bytes, std::uint64_t provenance_bytes,
                              std::uint64_t group_bytes) {
  VxlSectionSizes s;
  s.directions = std::uint64_t(m.stored_order_count) * sizeof(DirectionEntry);
  s.voxels = std::uint64_t(m.voxel_count) * sizeof(VoxelEntry);
  s.vertices = m.vertex_count * 3 * sizeof(float);
  s.orders = order_bytes;
  s.voxlines = m.voxline_count * sizeof(VoxlineEntry);
  s.streamlines = (m.streamline_count + 1) * sizeof(std::uint64_t);
  s.provenance = provenance_bytes;
  s.groups = group_bytes;
  return s;
}

VxlWriter::VxlWriter(const std::string& path, const VxlSectionSizes& sizes) : out_(path) {
  struct Planned {
    const char* id;
    std::uint32_t flags;
    std::uint64_t size;
  };
  std::vector<Planned> planned = {
      {"META", kSectionRequired, sizeof(MetaSection)}, {"DIRS", kSectionRequired, sizes.directions},
      {"VOXT", kSectionRequired, sizes.voxels},        {"VERT", kSectionRequired, sizes.vertices},
      {"ORDR", kSectionRequired, sizes.orders},        {"VXLN", kSectionRequired, sizes.voxlines},
      {"STRM", kSectionRequired, sizes.streamlines},   {"PROV", 0, sizes.provenance},
  };
  if (sizes.groups > 0) planned.push_back({"GRPS", 0, sizes.groups});

  // Header and table first, then each payload padded to a multiple of 64 (spec §2).
  std::uint64_t position = align_up(sizeof(FileHeader) + planned.size() * sizeof(SectionEntry), kVxlAlignment);
  for (const Planned& p : planned) {
    SectionEntry e{};
    std::memcpy(e.id, p.id, 4);
    e.flags = p.flags;
    e.offset = position;
    e.size = p.size;
    table_.push_back(e);
    position = align_up(position + p.size, kVxlAlignment);
  }
  file_ = out_.map(position);
}

std::span<std::uint8_t> VxlWriter::payload(Index i) {
  if (i >= table_.size()) return {};
  return file_.subspan(table_[i].offset, table_[i].size);
}

void VxlWriter::set_meta(const MetaSection& meta) {
  MetaSection m = meta;
  std::memset(m.reserved, 0, sizeof m.reserved);
  std::memcpy(payload(kMeta).data(), &m, sizeof m);
}

void VxlWriter::checksum_vertices_now() {
  table_[kVert].checksum = xxh3_64(file_.data() + table_[kVert].offset, table_[kVert].size);
  vertices_checksummed_ = true;
}

void VxlWriter::commit(unsigned threads) {
  // Largest payloads first, so that the big ones (VERT, ORDR) run side by side.
  std::vector<std::size_t> by_size;
  for (std::size_t i = 0; i < table_.size(); ++i)
    if (!(i == kVert && vertices_checksummed_)) by_size.push_back(i);
  std::stable_sort(by_size.begin(), by_size.end(), [&](std::size_t a, std::size_t b) { return table_[a].size > table_[b].size; });
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t k; (k = next++) < by_size.size();) {
      SectionEntry& e = table_[by_size[k]];
      e.checksum = xxh3_64(file_.data() + e.offset, e.size);
    }
  };
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < std::min<std::size_t>(threads, table_.size()); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();

  FileHeader h{};
  std::memcpy(h.magic, kVxlMagic.data(), 8);
  h.version_major = kVxlVersionMajor;
  h.version_minor = kVxlVersionMinor;
  h.header_size = sizeof(FileHeader);
  h.file_size = file_.size();
  h.section_table_offset = sizeof(FileHeader);
  h.section_count = static_cast<std::uint32_t>(table_.size());
  h.flags = 0;
  h.header_checksum = 0;  // covered with this field zero (spec §3)
  const std::size_t table_bytes = table_.size() * sizeof(SectionEntry);
  std::memcpy(file_.data(), &h, sizeof h);
  std::memcpy(file_.data() + sizeof h, table_.data(), table_bytes);
  h.header_checksum = xxh3_64(file_.data(), sizeof h + table_bytes);
  std::memcpy(file_.data(), &h, sizeof h);
  file_ = {};
  out_.commit();
}

void write_vxl(const std::string& path, const VxlContent& c) {
  std::vector<std::uint8_t> groups_bytes;
  if (!c.groups.empty()) groups_bytes = encode_groups(c.groups);
  VxlSectionSizes sizes;
  sizes.directions = c.directions.size_bytes();
  sizes.voxels = c.voxels.size_bytes();
  sizes.vertices = c.vertices.size_bytes();
  sizes.orders = c.orders.size_bytes();
  sizes.voxlines = c.voxlines.size_bytes();
  sizes.streamlines = c.streamline_first_voxline.size_bytes();
  sizes.provenance = c.provenance_json.size();
  sizes.groups = groups_bytes.size();

  VxlWriter w(path, sizes);
  auto copy = [](auto dst, const void* src) {
    if (!dst.empty()) std::memcpy(dst.data(), src, dst.size_bytes());
  };
  w.set_meta(c.meta);
  copy(w.directions(), c.directions.data());
  copy(w.voxels(), c.voxels.data());
  copy(w.vertices(), c.vertices.data());
  copy(w.orders(), c.orders.data());
  copy(w.voxlines(), c.voxlines.data());
  copy(w.streamline_first_voxline(), c.streamline_first_voxline.data());
  copy(w.provenance(), c.provenance_json.data());
  copy(w.groups(), groups_bytes.data());
  w.commit();
}

}  // namespace vxl
