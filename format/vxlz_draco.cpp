#include "vxlz_draco.h"

#include <array>
#include <cstring>

#include <draco/compression/decode.h>
#include <draco/compression/expert_encode.h>
#include <draco/point_cloud/point_cloud_builder.h>

#include "error.h"

namespace vxl {

std::vector<std::uint8_t> encode_residual_chunk(std::span<const std::int32_t> xyz) {
  const std::size_t n = xyz.size() / 3;
  draco::PointCloudBuilder builder;
  builder.Start(static_cast<draco::PointIndex::ValueType>(n));
  const int att = builder.AddAttribute(draco::GeometryAttribute::GENERIC, 3, draco::DT_INT32);
  if (n > 0) builder.SetAttributeValuesForAllPoints(att, xyz.data(), 0);
  // No deduplication: it would merge points with equal residuals and change the point count and order.
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
    throw Error(ErrorKind::Output, "", std::nullopt, std::string("Draco could not encode a chunk: ") + status.error_msg());
  return {reinterpret_cast<const std::uint8_t*>(buffer.data()),
          reinterpret_cast<const std::uint8_t*>(buffer.data()) + buffer.size()};
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

void decode_residual_chunk(std::span<const std::uint8_t> bytes, std::span<std::int32_t> xyz, const std::string& file,
                           std::uint64_t offset) {
  const std::size_t n = xyz.size() / 3;
  auto fail = [&](const std::string& what) { fail_input(file, offset, "position chunk: " + what); };
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  draco::Decoder decoder;
  auto result = decoder.DecodePointCloudFromBuffer(&buffer);
  if (!result.ok()) fail(std::string("not a Draco point cloud (") + result.status().error_msg() + ")");
  std::unique_ptr<draco::PointCloud> cloud = std::move(result).value();
  if (cloud->num_points() != n)
    fail("Draco point cloud holds " + std::to_string(cloud->num_points()) + " points, expected " + std::to_string(n));
  if (cloud->num_attributes() != 1) fail("expected exactly one Draco attribute");
  const draco::PointAttribute* att = cloud->attribute(0);
  if (att == nullptr || att->buffer() == nullptr || att->data_type() != draco::DT_INT32 || att->num_components() != 3)
    fail("expected a 3-component int32 Draco attribute");
  if (n == 0) return;
  // Sequentially decoded clouds map point i to value i; read the values in place when they are laid out
  // densely, else one by one through the mapping.
  const std::size_t stride = 3 * sizeof(std::int32_t);
  if (att->is_mapping_identity() && att->byte_stride() == stride && att->byte_offset() == 0 && att->size() == n &&
      att->buffer()->data_size() >= n * stride) {
    std::memcpy(xyz.data(), att->buffer()->data(), n * stride);
    return;
  }
  if (!att->is_mapping_identity() && att->indices_map_size() < n) fail("Draco attribute maps fewer values than points");
  for (std::size_t i = 0; i < n; ++i) {
    std::array<std::int32_t, 3> v;
    if (!att->GetValue<std::int32_t, 3>(att->mapped_index(draco::PointIndex(static_cast<std::uint32_t>(i))), &v))
      fail("Draco attribute value " + std::to_string(i) + " lies outside its buffer");
    std::memcpy(xyz.data() + 3 * i, v.data(), sizeof v);
  }
}

}  // namespace vxl
