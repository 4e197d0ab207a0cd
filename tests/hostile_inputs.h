// Hostile source files, written by code so that the test tree holds no binary data: each function writes
// one damaged or malicious file (or FIFO) to `path`. They stay small on disk; the bombs among them would
// inflate to tens of MiB, which the readers refuse long before.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <zlib.h>

#include <gtest/gtest.h>

#include "format/base/error.h"
#include "tests/mrtrix_test_files.h"
#include "tests/vtk_test_files.h"
#include "tests/zip_writer.h"

namespace vxl::test::hostile {

// The error `read` throws, or a failure when it throws none.
template <typename Read>
vxl::Error error_of(Read read) {
  try {
    read();
  } catch (const vxl::Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error";
  return vxl::Error(vxl::ErrorKind::Usage, "", std::nullopt, "no error");
}

inline void write_file(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// ---- gzip ----

// One gzip member holding `data`; with `finish` false the stream is flushed to a byte boundary (all of
// `data` can be inflated) but has no final block and no CRC trailer: a .gz cut short.
inline std::string gzip(const std::string& data, bool finish = true) {
  z_stream z{};
  deflateInit2(&z, 9, Z_DEFLATED, 16 + MAX_WBITS, 9, Z_DEFAULT_STRATEGY);
  std::string out(deflateBound(&z, data.size()) + 64, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = static_cast<uInt>(data.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  deflate(&z, finish ? Z_FINISH : Z_FULL_FLUSH);
  out.erase(out.size() - z.avail_out);  // erase, not resize: it never grows the string
  deflateEnd(&z);
  return out;
}

// ---- TRK ----

// A valid little-endian version 2 TRK header: 1 mm voxels, RAS, identity vox_to_ras, no scalars.
inline std::string trk_header(std::int32_t n_count = 0) {
  std::string h(1000, '\0');
  auto put = [&](std::size_t off, auto v) { std::memcpy(h.data() + off, &v, sizeof v); };
  std::memcpy(h.data(), "TRACK", 5);
  for (int i = 0; i < 3; ++i) put(6 + 2 * i, std::int16_t{100});
  for (int i = 0; i < 3; ++i) put(12 + 4 * i, 1.0f);
  for (int i = 0; i < 4; ++i) put(440 + 4 * (4 * i + i), 1.0f);
  std::memcpy(h.data() + 948, "RAS", 3);
  put(988, n_count);
  put(992, std::int32_t{2});
  put(996, std::int32_t{1000});
  return h;
}

// One record of `n` points (x = y = z = k + 1 for point k).
inline std::string trk_record(std::int32_t n) {
  std::string r = raw<std::int32_t>({n});
  for (std::int32_t k = 0; k < n; ++k) {
    const float v = static_cast<float>(k + 1);
    r += raw<float>({v, v, v});
  }
  return r;
}

// A header, then `mib` MiB of zeros where records should be, as concatenated gzip members (each
// MiB of zeros deflates to about 1 KiB, so the file stays small).
inline void trk_gz_zeros(const std::string& path, int mib) {
  const std::string zeros = gzip(std::string(1u << 20, '\0'));
  std::string out = gzip(trk_header());
  for (int i = 0; i < mib; ++i) out += zeros;
  write_file(path, out);
}

// Valid one-point records, `mib` MiB of them, that deflate about 1000:1: a bomb of real-looking data.
inline void trk_gz_record_bomb(const std::string& path, int mib) {
  std::string records;
  const std::string one = trk_record(1);
  while (records.size() + one.size() <= (1u << 20)) records += one;
  const std::string member = gzip(records);
  std::string out = gzip(trk_header());
  for (int i = 0; i < mib; ++i) out += member;
  write_file(path, out);
}

// Three records whose gzip stream is cut at a record boundary (no end of stream, no CRC).
inline void trk_gz_cut_at_record(const std::string& path, std::int32_t n_count) {
  write_file(path, gzip(trk_header(n_count) + trk_record(2) + trk_record(3) + trk_record(1), /*finish=*/false));
}

// A complete gzip stream followed by `tail`.
inline void trk_gz_with_tail(const std::string& path, const std::string& tail) {
  write_file(path, gzip(trk_header() + trk_record(2) + trk_record(3)) + tail);
}

// ---- TRX ----

template <typename T>
Bytes le(const std::vector<T>& values) {
  Bytes out(values.size() * sizeof(T));
  std::memcpy(out.data(), values.data(), out.size());  // the test machines are little-endian, like TRX
  return out;
}
inline Bytes text(const std::string& s) { return Bytes(s.begin(), s.end()); }

// A valid TRX of `n` streamlines of 2 points each, plus `extra` members.
inline std::vector<ZipEntry> trx_entries(std::uint32_t n, std::vector<ZipEntry> extra = {}) {
  std::vector<float> positions(6 * n, 1.0f);
  std::vector<std::uint64_t> offsets;
  for (std::uint32_t i = 0; i <= n; ++i) offsets.push_back(2 * i);
  std::vector<ZipEntry> e = {stored_entry("header.json", text("{\"NB_STREAMLINES\": " + std::to_string(n) +
                                                              ", \"NB_VERTICES\": " + std::to_string(2 * n) + "}")),
                             stored_entry("positions.3.float32", le(positions)),
                             stored_entry("offsets.uint64", le(offsets))};
  for (ZipEntry& x : extra) e.push_back(std::move(x));
  return e;
}

// A dps member whose component count does not fit in 64 bits.
inline void trx_huge_component_count(const std::string& path) {
  write_zip(path,
            trx_entries(3, {stored_entry("dps/c.99999999999999999999.float32", le(std::vector<float>{1, 2, 3}))}));
}

// The offsets member replaced by `mib` MiB of deflated zeros. With `honest` the zip's directory
// declares that size; otherwise it declares the 32 bytes the header asks for, and the data inflates past it.
inline void trx_offsets_bomb(const std::string& path, int mib, bool honest) {
  std::vector<ZipEntry> e = trx_entries(3);
  ZipEntry bomb = deflated_zeros_entry("offsets.uint64", std::uint64_t(mib) << 20);
  if (!honest) bomb.size = 4 * 8;
  e[2] = std::move(bomb);
  write_zip(path, e);
}

// Arrays nested `depth` deep: `[[[...]]]`.
inline std::string nested_json(std::size_t depth) { return std::string(depth, '[') + std::string(depth, ']'); }

// A valid TRX of 3 streamlines whose header.json also holds arrays nested `depth` deep.
inline void trx_deep_header(const std::string& path, std::size_t depth) {
  std::vector<ZipEntry> e = trx_entries(3);
  e[0] = stored_entry("header.json",
                      text("{\"NB_STREAMLINES\": 3, \"NB_VERTICES\": 6, \"deep\": " + nested_json(depth) + "}"));
  write_zip(path, e);
}

// ---- VTK and VTP ----

// A legacy VTK whose POINTS count N makes 3 x N wrap past 2^64: the data holds exactly as many numbers
// as the wrapped product, then one line over the first two points.
inline void vtk_points_count_wraps(const std::string& path, std::uint64_t n, bool binary) {
  const std::uint64_t wrapped = 3 * n;  // unsigned: wraps on purpose
  std::string s = "# vtk DataFile Version 3.0\nhostile\n" + std::string(binary ? "BINARY" : "ASCII") +
                  "\nDATASET POLYDATA\nPOINTS " + std::to_string(n) + " float\n";
  for (std::uint64_t k = 0; k < wrapped; ++k)
    s += binary ? test::be(static_cast<float>(k + 1)) : std::to_string(k + 1) + " ";
  s += "\nLINES 1 3\n";
  s += binary ? test::be<std::int32_t>(2) + test::be<std::int32_t>(0) + test::be<std::int32_t>(1) : "2 0 1";
  write_file(path, s + "\n");
}

// The small VTP tractogram (3 lines, a 2-component cell array) with extra cell counts in its Piece:
// `verts`, `polys` and `strips` chosen so that the sum of all cells wraps past 2^64 back to 3, the number
// of cell tuples the file holds.
inline void vtp_cell_count_wraps(const std::string& path, std::uint64_t verts, std::uint64_t polys,
                                 std::uint64_t strips) {
  std::string s = test::small_vtp({});
  const std::string lines = "NumberOfLines=\"3\"";
  s.replace(s.find(lines), lines.size(),
            lines + " NumberOfVerts=\"" + std::to_string(verts) + "\" NumberOfPolys=\"" + std::to_string(polys) +
                "\" NumberOfStrips=\"" + std::to_string(strips) + "\"");
  write_file(path, s);
}

// The small VTP tractogram in `style` whose Piece claims `points` points: more than its arrays hold.
inline void vtp_points_beyond_arrays(const std::string& path, const test::VtpStyle& style, std::uint64_t points) {
  std::string s = test::small_vtp(style);
  const std::string declared = "NumberOfPoints=\"5\"";
  s.replace(s.find(declared), declared.size(), "NumberOfPoints=\"" + std::to_string(points) + "\"");
  write_file(path, s);
}

// A legacy VTK of one 2-point line with one point-data array per name in `names`, each written as given
// (VTK's %XX escapes and all).
inline void vtk_point_arrays_named(const std::string& path, const std::vector<std::string>& names) {
  std::string s =
      "# vtk DataFile Version 3.0\nnames\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n0 0 0 1 1 1\n"
      "LINES 1 3\n2 0 1\nPOINT_DATA 2\n";
  for (const std::string& name : names) s += "SCALARS " + name + " float 1\nLOOKUP_TABLE default\n1 2\n";
  write_file(path, s);
}

// A VTP of one 2-point line whose points are one zlib block (appended, raw) with `junk` after the zlib
// stream, inside the block's declared compressed size; with no junk, a valid file.
inline void vtp_zlib_block_with_junk(const std::string& path, const std::string& junk) {
  const std::string points =
      test::le(0.0f) + test::le(0.0f) + test::le(0.0f) + test::le(1.0f) + test::le(2.0f) + test::le(3.0f);
  const std::string block = test::zlib_compress(points) + junk;
  const std::string header = test::le<std::uint32_t>(1) + test::le<std::uint32_t>(24) + test::le<std::uint32_t>(0) +
                             test::le(static_cast<std::uint32_t>(block.size()));
  write_file(path,
             "<VTKFile type=\"PolyData\" byte_order=\"LittleEndian\" compressor=\"vtkZLibDataCompressor\">"
             "<PolyData><Piece NumberOfPoints=\"2\" NumberOfLines=\"1\"><Points><DataArray type=\"Float32\" "
             "NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/></Points><Lines>"
             "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1</DataArray>"
             "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">2</DataArray></Lines></Piece></PolyData>"
             "<AppendedData encoding=\"raw\">_" +
                 header + block + "</AppendedData></VTKFile>");
}

// ---- MRtrix (TCK, TSF) ----

// A TSF of three streamlines of one value each, the second 1e300 (beyond float32).
inline void tsf_float64_out_of_range(const std::string& path) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  write_mrtrix_file(path, "mrtrix track scalars", "Float64LE", raw<double>({1, nan, 1e300, nan, 3, nan, inf}));
}

// A TSF of three streamlines whose header says count: 99.
inline void tsf_wrong_count(const std::string& path) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  write_mrtrix_file(path, "mrtrix track scalars", "Float32LE", raw<float>({1, nan, 2, nan, 3, nan, inf}),
                    "count: 99\n");
}

// A TCK of one streamline, then a point whose x alone is Inf (a damaged point, which ends the
// data), then another streamline that is lost.
inline void tck_inf_in_one_coordinate(const std::string& path) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  write_mrtrix_file(path, "mrtrix tracks", "Float32LE",
                    raw<float>({1, 2, 3, 4, 5, 6, nan, nan, nan, inf, 7, 8, 9, 9, 9, nan, nan, nan, inf, inf, inf}));
}

// A TCK whose data goes on after its (Inf, Inf, Inf) terminator.
inline void tck_data_after_terminator(const std::string& path) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  write_mrtrix_file(path, "mrtrix tracks", "Float32LE",
                    raw<float>({1, 2, 3, 4, 5, 6, nan, nan, nan, inf, inf, inf, 7, 8, 9, 9, 9, 9, nan, nan, nan}));
}

// A TCK of one streamline whose header says count: -5.
inline void tck_negative_count(const std::string& path) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  write_mrtrix_file(path, "mrtrix tracks", "Float32LE", raw<float>({1, 2, 3, 4, 5, 6, nan, nan, nan, inf, inf, inf}),
                    "count: -5\n");
}

// A FIFO, which no writer will ever open.
inline void fifo(const std::string& path) { ::mkfifo(path.c_str(), 0600); }

}  // namespace vxl::test::hostile
