// MRtrix images (.mif, .mih + data) written by the tests themselves: a header with the chosen layout,
// datatype and transform, and the voxels stored in that layout's order.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace vxl::test {

struct MifSpec {
  std::vector<std::int64_t> dims;  // x first
  std::vector<double> vox;         // mm, one per axis
  std::vector<int> layout;         // per axis: +-(rank + 1), e.g. {-1, 2, 3} for "-0,+1,+2"
  std::array<double, 12> transform{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};  // rigid part, row-major 3 x 4
  std::string datatype = "Int16LE";  // Int16LE, Float32LE, UInt8 or Bit (the header only)
  std::string extra;                 // more header lines, each ending in '\n'
};

// The stored bytes of `values` (the logical voxels, x fastest, all axes) in `spec`'s layout.
inline std::string mif_data(const MifSpec& spec, const std::vector<double>& values) {
  const std::size_t axes = spec.dims.size();
  std::vector<std::int64_t> stride(axes);
  std::int64_t step = 1;
  for (std::size_t rank = 0; rank < axes; ++rank)
    for (std::size_t a = 0; a < axes; ++a)
      if (std::abs(spec.layout[a]) == int(rank) + 1) stride[a] = step, step *= spec.dims[a];
  const std::size_t size = spec.datatype == "Float32LE" ? 4 : spec.datatype == "Int16LE" ? 2 : 1;
  std::string out(std::size_t(step) * size, '\0');
  std::vector<std::int64_t> index(axes, 0);
  for (double v : values) {
    std::int64_t at = 0;
    for (std::size_t a = 0; a < axes; ++a)
      at += (spec.layout[a] < 0 ? spec.dims[a] - 1 - index[a] : index[a]) * stride[a];
    char* p = out.data() + std::size_t(at) * size;
    if (size == 4) {
      const float f = static_cast<float>(v);
      std::memcpy(p, &f, 4);
    } else if (size == 2) {
      const std::int16_t s = static_cast<std::int16_t>(v);
      std::memcpy(p, &s, 2);
    } else {
      *p = static_cast<char>(v);
    }
    for (std::size_t a = 0; a < axes; ++a) {
      if (++index[a] < spec.dims[a]) break;
      index[a] = 0;
    }
  }
  return out;
}

inline std::string mif_list(const std::vector<std::int64_t>& v) {
  std::string s;
  for (std::int64_t x : v) s += (s.empty() ? "" : ",") + std::to_string(x);
  return s;
}

// The header lines from "mrtrix image" to the datatype and transform (no file: line, no END).
inline std::string mif_header_fields(const MifSpec& spec) {
  std::string h = "mrtrix image\ndim: " + mif_list(spec.dims) + "\nvox: ";
  for (std::size_t a = 0; a < spec.vox.size(); ++a) h += (a ? "," : "") + std::to_string(spec.vox[a]);
  h += "\nlayout: ";
  for (std::size_t a = 0; a < spec.layout.size(); ++a)
    h += std::string(a ? "," : "") + (spec.layout[a] < 0 ? "-" : "+") + std::to_string(std::abs(spec.layout[a]) - 1);
  h += "\ndatatype: " + spec.datatype + "\n";
  for (int r = 0; r < 3; ++r) {
    h += "transform: ";
    for (int c = 0; c < 4; ++c) h += (c ? ", " : "") + std::to_string(spec.transform[4 * r + c]);
    h += "\n";
  }
  return h + spec.extra;
}

// A whole .mif: the header, "file: . OFFSET", END, padding, then the data.
inline std::string mif_bytes(const MifSpec& spec, const std::vector<double>& values) {
  const std::string fields = mif_header_fields(spec);
  // The offset's digits change the header's length: aim past it.
  const std::size_t offset = (fields.size() + 32 + 15) / 16 * 16;
  std::string h = fields + "file: . " + std::to_string(offset) + "\nEND\n";
  h.resize(offset, '\0');
  return h + mif_data(spec, values);
}

// A .mih header naming `data_name` (beside it) for its data; with no END line, as mrconvert writes one.
inline std::string mih_header(const MifSpec& spec, const std::string& data_name, bool end_line = false) {
  return mif_header_fields(spec) + "file: " + data_name + (end_line ? "\nEND\n" : "\n");
}

}  // namespace vxl::test
