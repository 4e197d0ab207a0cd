// Writers of small legacy VTK and VTP files for the reader tests: one tractogram in every encoding.
#pragma once

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <zlib.h>

namespace vxl::test {

inline void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// Big-endian bytes of a value.
template <typename T>
std::string be(T v) {
  std::string s(sizeof v, '\0');
  std::memcpy(s.data(), &v, sizeof v);
  return {s.rbegin(), s.rend()};
}
template <typename T>
std::string le(T v) {
  std::string s(sizeof v, '\0');
  std::memcpy(s.data(), &v, sizeof v);
  return s;
}

inline std::string base64(const std::string& in) {
  static const char* a = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < in.size(); i += 3) {
    std::uint32_t v = std::uint32_t(std::uint8_t(in[i])) << 16;
    if (i + 1 < in.size()) v |= std::uint32_t(std::uint8_t(in[i + 1])) << 8;
    if (i + 2 < in.size()) v |= std::uint8_t(in[i + 2]);
    out += a[v >> 18];
    out += a[(v >> 12) & 63];
    out += i + 1 < in.size() ? a[(v >> 6) & 63] : '=';
    out += i + 2 < in.size() ? a[v & 63] : '=';
  }
  return out;
}

inline std::string zlib_compress(const std::string& in) {
  uLongf n = compressBound(in.size());
  std::string out(n, '\0');
  compress(reinterpret_cast<Bytef*>(out.data()), &n, reinterpret_cast<const Bytef*>(in.data()), in.size());
  out.resize(n);
  return out;
}

// How a VTP file encodes its arrays.
struct VtpStyle {
  std::string format = "binary";  // ascii, binary, appended
  bool appended_base64 = false;
  bool zlib = false;
  bool uint64_header = false;
  bool big_endian = false;
  std::size_t block_size = 32;  // small, so that arrays span several compressed blocks
};

// A VTP writer for float32 points, int32 connectivity/offsets, float32 (or multi-component) arrays.
class VtpBuilder {
 public:
  explicit VtpBuilder(VtpStyle s) : s_(s) {}

  template <typename T>
  std::string data_array(const std::string& type, const std::string& name, int components, const std::vector<T>& v) {
    std::string raw;
    for (T x : v) raw += s_.big_endian ? be(x) : le(x);
    std::string head = "<DataArray type=\"" + type + "\" Name=\"" + name + "\" NumberOfComponents=\"" +
                       std::to_string(components) + "\" format=\"" + s_.format + "\"";
    if (s_.format == "ascii") {
      std::ostringstream text;
      text.precision(9);  // enough for float32 to round-trip
      for (T x : v) text << x << ' ';
      return head + ">" + text.str() + "</DataArray>\n";
    }
    const std::string header_and_data = encode(raw);
    if (s_.format == "binary") return head + ">\n" + header_and_data + "\n</DataArray>\n";
    head += " offset=\"" + std::to_string(appended_.size()) + "\"/>\n";
    appended_ += header_and_data;
    return head;
  }

  std::string file(const std::string& piece_attributes, const std::string& body) const {
    std::string x = "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"" +
                    std::string(s_.big_endian ? "BigEndian" : "LittleEndian") + "\" header_type=\"" +
                    (s_.uint64_header ? "UInt64" : "UInt32") + "\"" +
                    (s_.zlib ? " compressor=\"vtkZLibDataCompressor\"" : "") + ">\n<PolyData>\n<Piece " +
                    piece_attributes + ">\n" + body + "</Piece>\n</PolyData>\n";
    if (s_.format == "appended")
      x += "<AppendedData encoding=\"" + std::string(s_.appended_base64 ? "base64" : "raw") + "\">\n   _" + appended_ +
           "\n</AppendedData>\n";
    return x + "</VTKFile>\n";
  }

 private:
  std::string uint(std::uint64_t v) const {
    if (s_.uint64_header) return s_.big_endian ? be(v) : le(v);
    return s_.big_endian ? be(static_cast<std::uint32_t>(v)) : le(static_cast<std::uint32_t>(v));
  }
  // VTK's layout: a header (byte count, or the compression header), then the data; base64 encodes the two
  // as separate chunks.
  std::string encode(const std::string& raw) const {
    std::string header, data;
    if (!s_.zlib) {
      header = uint(raw.size());
      data = raw;
    } else {
      const std::size_t blocks = (raw.size() + s_.block_size - 1) / s_.block_size;
      std::string sizes;
      for (std::size_t b = 0; b < blocks; ++b) {
        std::string c = zlib_compress(raw.substr(b * s_.block_size, s_.block_size));
        sizes += uint(c.size());
        data += c;
      }
      header = uint(blocks) + uint(s_.block_size) + uint(raw.size() % s_.block_size) + sizes;
    }
    const bool b64 = s_.format == "binary" || s_.appended_base64;
    return b64 ? base64(header) + base64(data) : header + data;
  }

  VtpStyle s_;
  std::string appended_;
};

// The tractogram of the synthetic files: 3 streamlines (3, 1 and 2 points) over 5 points, the third
// streamline using points out of order and twice, one point data array, one 2-component cell data array.
struct SmallPolyData {
  std::vector<float> points = {0.5f, 1.25f, -2.0f, 1.0f / 3.0f, 4.0f,  5.0f,  -7.5f, 8.0f,
                               9.0f, 10.0f, 11.0f, 12.0f,       1e-7f, -0.0f, 3.0f};
  std::vector<std::int32_t> connectivity = {0, 1, 2, 4, 3, 0};
  std::vector<std::int32_t> offsets = {3, 4, 6};  // VTP: end offsets
  std::vector<float> point_values = {1, 2, 3, 4, 5};
  std::vector<float> cell_values = {10, 11, 20, 21, 30, 31};  // 2 components
};

inline std::string small_vtp(const VtpStyle& style) {
  SmallPolyData d;
  VtpBuilder b(style);
  std::string body = "<PointData>\n" + b.data_array("Float32", "fa", 1, d.point_values) + "</PointData>\n";
  body += "<CellData>\n" + b.data_array("Float32", "rgb", 2, d.cell_values) + "</CellData>\n";
  body += "<Points>\n" + b.data_array("Float32", "Points", 3, d.points) + "</Points>\n";
  body += "<Lines>\n" + b.data_array("Int32", "connectivity", 1, d.connectivity) +
          b.data_array("Int32", "offsets", 1, d.offsets) + "</Lines>\n";
  return b.file("NumberOfPoints=\"5\" NumberOfLines=\"3\"", body);
}

}  // namespace vxl::test
