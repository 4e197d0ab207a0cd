// Recomputes the checksums of a damaged .vxl or .vxlz (a package's per position chunk, every section's, then the
// header's), so that the
// damage gets past the checksum checks and reaches the decoders and structure checks behind them. Used by
// the damage tests and by the fuzz targets. Safe on arbitrary bytes: entries that point outside the buffer
// are left alone (the reader refuses those anyway).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "format/base/checksum.h"
#include "format/vxl_layout.h"

namespace vxl::test {

// A package's checksum per position chunk (CHKS), recomputed from the chunk sizes (CHNK) over the positions (POSD),
// as far as those lie inside the buffer.
template <typename Byte>
void reseal_chunk_checksums(Byte* bytes, std::size_t size, const FileHeader& h) {
  if (h.section_count > kVxlMaxSections || sizeof h + std::uint64_t(h.section_count) * sizeof(SectionEntry) > size)
    return;
  const SectionEntry *chnk = nullptr, *chks = nullptr, *posd = nullptr;
  SectionEntry entries[kVxlMaxSections];
  for (std::uint32_t i = 0; i < h.section_count; ++i) {
    std::memcpy(&entries[i], bytes + sizeof h + i * sizeof(SectionEntry), sizeof(SectionEntry));
    const SectionEntry& e = entries[i];
    if (e.offset > size || e.size > size - e.offset) continue;
    if (std::memcmp(e.id, "CHNK", 4) == 0) chnk = &e;
    if (std::memcmp(e.id, "CHKS", 4) == 0) chks = &e;
    if (std::memcmp(e.id, "POSD", 4) == 0) posd = &e;
  }
  if (!chnk || !chks || !posd) return;
  std::uint64_t at = posd->offset;
  for (std::uint64_t i = 0; i < chks->size / 8 && i < chnk->size / 16; ++i) {
    std::uint64_t sizes[2];
    std::memcpy(sizes, bytes + chnk->offset + 16 * i, 16);
    const std::uint64_t end = posd->offset + posd->size;
    if (sizes[0] > end - at || sizes[1] > end - at - sizes[0]) return;
    const std::uint64_t checksum = xxh3_64(bytes + at, sizes[0] + sizes[1]);
    std::memcpy(bytes + chks->offset + 8 * i, &checksum, 8);
    at += sizes[0] + sizes[1];
  }
}

// Returns false when `bytes` is too short to hold the header and its section table.
template <typename Byte>
bool reseal_checksums(Byte* bytes, std::size_t size) {
  static_assert(sizeof(Byte) == 1);
  FileHeader h;
  if (size < sizeof h) return false;
  std::memcpy(&h, bytes, sizeof h);
  const std::uint64_t table_bytes = std::uint64_t(h.section_count) * sizeof(SectionEntry);
  if (h.section_count > kVxlMaxSections || sizeof h + table_bytes > size) return false;
  reseal_chunk_checksums(bytes, size, h);
  for (std::uint32_t i = 0; i < h.section_count; ++i) {
    SectionEntry e;
    std::memcpy(&e, bytes + sizeof h + i * sizeof e, sizeof e);
    if (e.offset > size || e.size > size - e.offset) continue;
    e.checksum = xxh3_64(bytes + e.offset, e.size);
    std::memcpy(bytes + sizeof h + i * sizeof e, &e, sizeof e);
  }
  h.header_checksum = 0;  // covered with this field zero (spec §3)
  std::memcpy(bytes, &h, sizeof h);
  h.header_checksum = xxh3_64(bytes, sizeof h + table_bytes);
  std::memcpy(bytes, &h, sizeof h);
  return true;
}

}  // namespace vxl::test
