// Recomputes the checksums of a damaged .vxl or .vxlz (every section's, then the header's), so that the
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

// Returns false when `bytes` is too short to hold the header and its section table.
template <typename Byte>
bool reseal_checksums(Byte* bytes, std::size_t size) {
  static_assert(sizeof(Byte) == 1);
  FileHeader h;
  if (size < sizeof h) return false;
  std::memcpy(&h, bytes, sizeof h);
  const std::uint64_t table_bytes = std::uint64_t(h.section_count) * sizeof(SectionEntry);
  if (h.section_count > kVxlMaxSections || sizeof h + table_bytes > size) return false;
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
