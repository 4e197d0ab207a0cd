// A minimal zip writer for test archives: stored or deflated members, no zip64, and the sizes in the
// directory under the test's control (a hostile archive may declare other sizes than its data has).
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <zlib.h>

namespace vxl::test {

using Bytes = std::vector<std::uint8_t>;

struct ZipEntry {
  std::string name;
  Bytes data;  // as stored in the archive: raw or raw-deflated
  bool deflated = false;
  std::uint32_t size = 0;  // uncompressed size the directory declares
  std::uint32_t crc = 0;
};

inline ZipEntry stored_entry(const std::string& name, const Bytes& data) {
  return {name, data, false, static_cast<std::uint32_t>(data.size()),
          static_cast<std::uint32_t>(::crc32(0, data.data(), static_cast<uInt>(data.size())))};
}

// `size` zero bytes, deflated a MiB at a time (without ever holding them whole).
inline ZipEntry deflated_zeros_entry(const std::string& name, std::uint64_t size) {
  ZipEntry e{name, {}, true, static_cast<std::uint32_t>(size), 0};
  z_stream z{};
  deflateInit2(&z, 1, Z_DEFLATED, -MAX_WBITS, 9, Z_DEFAULT_STRATEGY);  // raw deflate, as zip stores it
  const Bytes zeros(1u << 20, 0);
  uLong crc = ::crc32(0, nullptr, 0);
  Bytes out(1u << 16);
  for (std::uint64_t left = size;;) {
    const std::uint64_t n = std::min<std::uint64_t>(left, zeros.size());
    crc = ::crc32(crc, zeros.data(), static_cast<uInt>(n));
    left -= n;
    z.next_in = const_cast<Bytef*>(zeros.data());
    z.avail_in = static_cast<uInt>(n);
    const int flush = left == 0 ? Z_FINISH : Z_NO_FLUSH;
    int r;
    do {
      z.next_out = out.data();
      z.avail_out = static_cast<uInt>(out.size());
      r = deflate(&z, flush);
      e.data.insert(e.data.end(), out.data(), out.data() + (out.size() - z.avail_out));
    } while (z.avail_out == 0 || (flush == Z_FINISH && r != Z_STREAM_END));
    if (left == 0) break;
  }
  deflateEnd(&z);
  e.crc = static_cast<std::uint32_t>(crc);
  return e;
}

inline void write_zip(const std::string& path, const std::vector<ZipEntry>& entries) {
  Bytes out, central;
  auto put = [](Bytes& b, std::uint32_t v, int n) {
    for (int i = 0; i < n; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  };
  for (const ZipEntry& e : entries) {
    const std::uint32_t offset = static_cast<std::uint32_t>(out.size());
    const std::uint32_t comp = static_cast<std::uint32_t>(e.data.size());
    const std::uint16_t name_len = static_cast<std::uint16_t>(e.name.size());
    const std::uint32_t method = e.deflated ? 8 : 0;
    put(out, 0x04034b50, 4);  // local file header
    put(out, 20, 2);          // version needed
    put(out, 0, 2);           // flags
    put(out, method, 2);
    put(out, 0, 4);  // time, date
    put(out, e.crc, 4);
    put(out, comp, 4);
    put(out, e.size, 4);
    put(out, name_len, 2);
    put(out, 0, 2);  // extra length
    out.insert(out.end(), e.name.begin(), e.name.end());
    out.insert(out.end(), e.data.begin(), e.data.end());

    put(central, 0x02014b50, 4);  // central directory header
    put(central, 20, 2);          // version made by
    put(central, 20, 2);          // version needed
    put(central, 0, 2);
    put(central, method, 2);
    put(central, 0, 4);
    put(central, e.crc, 4);
    put(central, comp, 4);
    put(central, e.size, 4);
    put(central, name_len, 2);
    put(central, 0, 2);  // extra
    put(central, 0, 2);  // comment
    put(central, 0, 2);  // disk
    put(central, 0, 2);  // internal attributes
    put(central, 0, 4);  // external attributes
    put(central, offset, 4);
    central.insert(central.end(), e.name.begin(), e.name.end());
  }
  const std::uint32_t cd_offset = static_cast<std::uint32_t>(out.size());
  out.insert(out.end(), central.begin(), central.end());
  put(out, 0x06054b50, 4);  // end of central directory
  put(out, 0, 2);
  put(out, 0, 2);
  put(out, static_cast<std::uint32_t>(entries.size()), 2);
  put(out, static_cast<std::uint32_t>(entries.size()), 2);
  put(out, static_cast<std::uint32_t>(central.size()), 4);
  put(out, cd_offset, 4);
  put(out, 0, 2);
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
}

// Stored members only.
inline void write_zip(const std::string& path, const std::vector<std::pair<std::string, Bytes>>& members) {
  std::vector<ZipEntry> entries;
  for (const auto& [name, data] : members) entries.push_back(stored_entry(name, data));
  write_zip(path, entries);
}

// The same members as the files of a TRX directory (a TRX may be a folder instead of a zip).
inline void write_dir(const std::string& path, const std::vector<std::pair<std::string, Bytes>>& members) {
  for (const auto& [name, data] : members) {
    const std::filesystem::path p = std::filesystem::path(path) / name;
    std::filesystem::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary)
        .write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
  }
}

}  // namespace vxl::test
