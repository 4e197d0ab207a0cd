// draco_cloud_dump: decode one Draco point-cloud buffer and dump its attributes in a trivial binary form,
// so that scripts/vxlz_spec_reader.py (a second .vxlz reader written from spec/vxlz-package-v2.md alone)
// can use libdraco without Python bindings. Uses only libdraco's public API; no code of the project.
//
//   draco_cloud_dump BUFFER_FILE        (BUFFER_FILE "-" reads standard input)
//
// Output on stdout, all little-endian (the only hosts Draco and the spec target):
//   u32 point_count, u32 attribute_count,
//   then per attribute, in attribute order:
//     u32 attribute_type (draco::GeometryAttribute::Type: 0 POSITION … 4 GENERIC),
//     u32 data_type      (draco::DataType: 5 = DT_INT32),
//     u32 components,
//     point_count × components i32 values, point after point (value of point i through the attribute's
//       point-to-value map; converted to int32 by draco's ConvertValue, exact for DT_INT32).
// Exit 0 on success; 1 (message on stderr) when the buffer is not a point cloud (e.g. a mesh), does not
// decode, or an attribute cannot be converted; 2 on a usage or I/O error.
//
// Build: g++ -std=c++20 -O2 tests/spec/draco_cloud_dump.cpp -ldraco -o draco_cloud_dump
#include <draco/compression/decode.h>
#include <draco/point_cloud/point_cloud.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <vector>

static void put_u32(std::vector<char>& out, uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFF));
}

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: draco_cloud_dump BUFFER_FILE\n";
    return 2;
  }
  std::string path = argv[1];
  std::vector<char> data;
  if (path == "-") {
    data.assign(std::istreambuf_iterator<char>(std::cin), {});
  } else {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
      std::cerr << "draco_cloud_dump: cannot read " << path << "\n";
      return 2;
    }
    data.assign(std::istreambuf_iterator<char>(in), {});
  }
  draco::DecoderBuffer buffer;
  buffer.Init(data.data(), data.size());
  auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
  if (!type.ok()) {
    std::cerr << "draco_cloud_dump: not a Draco buffer: " << type.status().error_msg_string() << "\n";
    return 1;
  }
  if (type.value() != draco::POINT_CLOUD) {
    std::cerr << "draco_cloud_dump: the buffer holds geometry type " << type.value() << ", not a point cloud\n";
    return 1;
  }
  draco::Decoder decoder;
  auto decoded = decoder.DecodePointCloudFromBuffer(&buffer);
  if (!decoded.ok()) {
    std::cerr << "draco_cloud_dump: decoding failed: " << decoded.status().error_msg_string() << "\n";
    return 1;
  }
  const draco::PointCloud& pc = *decoded.value();
  const uint32_t n = pc.num_points();
  std::vector<char> out;
  put_u32(out, n);
  put_u32(out, static_cast<uint32_t>(pc.num_attributes()));
  for (int a = 0; a < pc.num_attributes(); ++a) {
    const draco::PointAttribute* att = pc.attribute(a);
    const int comps = att->num_components();
    put_u32(out, static_cast<uint32_t>(att->attribute_type()));
    put_u32(out, static_cast<uint32_t>(att->data_type()));
    put_u32(out, static_cast<uint32_t>(comps));
    std::vector<int32_t> v(comps);
    out.reserve(out.size() + size_t(n) * comps * 4);
    for (uint32_t i = 0; i < n; ++i) {
      if (!att->ConvertValue<int32_t>(att->mapped_index(draco::PointIndex(i)), comps, v.data())) {
        std::cerr << "draco_cloud_dump: attribute " << a << " value of point " << i << " not convertible\n";
        return 1;
      }
      for (int c = 0; c < comps; ++c) put_u32(out, static_cast<uint32_t>(v[c]));
    }
  }
  if (std::fwrite(out.data(), 1, out.size(), stdout) != out.size()) return 2;
  return 0;
}
