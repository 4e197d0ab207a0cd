#include "vxl_writer.h"

#include <cstring>

#include "atomic_output.h"
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

namespace {

struct PendingSection {
  const char* id;
  std::uint32_t flags;
  const void* data;
  std::uint64_t size;
};

}  // namespace

void write_vxl(const std::string& path, const VxlContent& c) {
  MetaSection meta = c.meta;
  std::memset(meta.reserved, 0, sizeof meta.reserved);
  std::vector<std::uint8_t> groups_bytes;
  if (!c.groups.empty()) groups_bytes = encode_groups(c.groups);

  std::vector<PendingSection> sections = {
      {"META", kSectionRequired, &meta, sizeof meta},
      {"DIRS", kSectionRequired, c.directions.data(), c.directions.size_bytes()},
      {"VOXT", kSectionRequired, c.voxels.data(), c.voxels.size_bytes()},
      {"VERT", kSectionRequired, c.vertices.data(), c.vertices.size_bytes()},
      {"ORDR", kSectionRequired, c.orders.data(), c.orders.size_bytes()},
      {"VXLN", kSectionRequired, c.voxlines.data(), c.voxlines.size_bytes()},
      {"STRM", kSectionRequired, c.streamline_first_voxline.data(), c.streamline_first_voxline.size_bytes()},
      {"PROV", 0, c.provenance_json.data(), c.provenance_json.size()},
  };
  if (!groups_bytes.empty()) sections.push_back({"GRPS", 0, groups_bytes.data(), groups_bytes.size()});

  AtomicOutputFile out(path);
  const std::uint64_t table_bytes = sections.size() * sizeof(SectionEntry);
  const std::uint64_t first_payload = align_up(sizeof(FileHeader) + table_bytes, kVxlAlignment);
  out.write_zeros(first_payload);  // header and table are written last, with their checksum

  std::vector<SectionEntry> table(sections.size());
  for (std::size_t i = 0; i < sections.size(); ++i) {
    const PendingSection& s = sections[i];
    SectionEntry& e = table[i];
    std::memcpy(e.id, s.id, 4);
    e.flags = s.flags;
    e.offset = out.position();
    e.size = s.size;
    e.checksum = xxh3_64(s.data, s.size);
    if (s.size > 0) out.write(s.data, s.size);
    out.write_zeros(align_up(out.position(), kVxlAlignment) - out.position());
  }

  FileHeader h{};
  std::memcpy(h.magic, kVxlMagic.data(), 8);
  h.version_major = kVxlVersionMajor;
  h.version_minor = kVxlVersionMinor;
  h.header_size = sizeof(FileHeader);
  h.file_size = out.position();
  h.section_table_offset = sizeof(FileHeader);
  h.section_count = static_cast<std::uint32_t>(sections.size());
  h.flags = 0;
  h.header_checksum = 0;
  std::vector<std::uint8_t> head(sizeof h + table_bytes);
  std::memcpy(head.data(), &h, sizeof h);
  std::memcpy(head.data() + sizeof h, table.data(), table_bytes);
  h.header_checksum = xxh3_64(head.data(), head.size());
  std::memcpy(head.data(), &h, sizeof h);
  out.pwrite(head.data(), head.size(), 0);
  out.commit();
}

}  // namespace vxl
