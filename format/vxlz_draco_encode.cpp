// The packing side of vxlz_draco.h: residual chunks encoded as Draco point clouds. Apart from the decoding side
// (vxlz_draco.cpp) so that a reader of packages (the web viewer) needs none of Draco's encoders.
#include "format/vxlz_draco.h"

#include <draco/compression/expert_encode.h>
#include <draco/point_cloud/point_cloud_builder.h>

#include "format/base/error.h"

namespace vxl {
namespace {

std::uint32_t zigzag(std::int32_t r) {
  return (static_cast<std::uint32_t>(r) << 1) ^ static_cast<std::uint32_t>(r >> 31);
}

// n points with one GENERIC int32 attribute of `components` components, sequentially encoded.
std::vector<std::uint8_t> encode_cloud(const std::int32_t* values, std::size_t n, int components) {
  draco::PointCloudBuilder builder;
  builder.Start(static_cast<draco::PointIndex::ValueType>(n));
  const int att = builder.AddAttribute(draco::GeometryAttribute::GENERIC, components, draco::DT_INT32);
  if (n > 0) builder.SetAttributeValuesForAllPoints(att, values, 0);
  // No deduplication: it would merge points with equal values and change the point count and order.
  std::unique_ptr<draco::PointCloud> cloud = builder.Finalize(false);
  if (!cloud) throw Error(ErrorKind::Output, "", std::nullopt, "Draco could not build a point cloud");

  draco::ExpertEncoder encoder(*cloud);
  // Sequential: the default k-d tree encoding reorders points. No prediction: the values are residuals of
  // our own predictor already. No quantisation is set, so Draco codes the integers losslessly.
  encoder.SetEncodingMethod(draco::POINT_CLOUD_SEQUENTIAL_ENCODING);
  encoder.SetAttributePredictionScheme(att, draco::PREDICTION_NONE);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeToBuffer(&buffer);
  if (!status.ok())
    throw Error(ErrorKind::Output, "", std::nullopt,
                std::string("Draco could not encode a chunk: ") + status.error_msg());
  return {reinterpret_cast<const std::uint8_t*>(buffer.data()),
          reinterpret_cast<const std::uint8_t*>(buffer.data()) + buffer.size()};
}

}  // namespace

std::uint32_t joint_symbol(const std::int32_t r[3], std::uint32_t joint_bits) {
  const std::uint32_t z0 = zigzag(r[0]), z1 = zigzag(r[1]), z2 = zigzag(r[2]);
  if ((z0 | z1 | z2) >> joint_bits) return 0;
  return 1 + z0 + (z1 << joint_bits) + (z2 << 2 * joint_bits);
}

EncodedChunk encode_residual_chunk(std::span<const std::int32_t> xyz, std::uint32_t joint_bits) {
  const std::size_t n = xyz.size() / 3;
  std::vector<std::int32_t> symbols(n), escapes;
  for (std::size_t i = 0; i < n; ++i) {
    symbols[i] = static_cast<std::int32_t>(joint_symbol(xyz.data() + 3 * i, joint_bits));
    if (symbols[i] == 0) escapes.insert(escapes.end(), xyz.begin() + 3 * i, xyz.begin() + 3 * i + 3);
  }
  EncodedChunk out;
  out.symbols = encode_cloud(symbols.data(), n, 1);
  if (!escapes.empty()) out.escapes = encode_cloud(escapes.data(), escapes.size() / 3, 3);
  return out;
}

std::size_t draco_native_size(std::span<const float> xyz, std::uint32_t bits, const float origin[3], float range) {
  const std::size_t n = xyz.size() / 3;
  draco::PointCloudBuilder builder;
  builder.Start(static_cast<draco::PointIndex::ValueType>(n));
  const int att = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  if (n > 0) builder.SetAttributeValuesForAllPoints(att, xyz.data(), 0);
  std::unique_ptr<draco::PointCloud> cloud = builder.Finalize(false);
  draco::ExpertEncoder encoder(*cloud);
  encoder.SetEncodingMethod(draco::POINT_CLOUD_SEQUENTIAL_ENCODING);
  encoder.SetAttributeExplicitQuantization(att, static_cast<int>(bits), 3, origin, range);
  draco::EncoderBuffer buffer;
  if (!encoder.EncodeToBuffer(&buffer).ok()) throw Error(ErrorKind::Output, "", std::nullopt, "Draco could not encode");
  return buffer.size();
}

}  // namespace vxl
