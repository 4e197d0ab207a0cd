#include "format/vxlz_draco.h"

#include <array>
#include <cstring>
#include <optional>

#include <draco/compression/decode.h>
#include <draco/compression/expert_encode.h>
#include <draco/compression/point_cloud/point_cloud_decoder.h>
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

// A decoded cloud of exactly n points with one int32 attribute of `components` components, its values
// dense in point order: read in place from Draco's buffer when it is laid out so (sequential decoding
// always is), else copied point by point through the attribute's mapping. Outside the anonymous namespace:
// ResidualChunk, declared in the header, holds two.
class DecodedCloud {
 public:
  DecodedCloud(std::span<const std::uint8_t> bytes, std::size_t n, int components, const char* what,
               const std::string& file, std::uint64_t offset) {
    auto fail = [&](const std::string& message) { fail_input(file, offset, std::string(what) + ": " + message); };
    // Draco sizes its buffers by the point count the stream states: check it against ours before Draco
    // allocates anything (a stream with valid package checksums but a damaged count asked for 6 GB).
    // What we write: a sequentially encoded point cloud without metadata, whose geometry data is the
    // point count as an int32 right after the header.
    draco::DecoderBuffer probe;
    probe.Init(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    draco::DracoHeader header;
    if (!draco::PointCloudDecoder::DecodeHeader(&probe, &header).ok()) fail("not a Draco point cloud (bad header)");
    if (header.encoder_type != draco::POINT_CLOUD || header.encoder_method != draco::POINT_CLOUD_SEQUENTIAL_ENCODING ||
        (header.flags & METADATA_FLAG_MASK) != 0)
      fail("expected a sequentially encoded Draco point cloud without metadata");
    std::int32_t stated_points = 0;
    if (!probe.Decode(&stated_points)) fail("Draco point cloud ends before its point count");
    if (stated_points < 0 || static_cast<std::uint64_t>(stated_points) != n)
      fail("Draco point cloud states " + std::to_string(stated_points) + " points, expected " + std::to_string(n));

    draco::DecoderBuffer buffer;
    buffer.Init(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    draco::Decoder decoder;
    auto result = decoder.DecodePointCloudFromBuffer(&buffer);
    if (!result.ok()) fail(std::string("not a Draco point cloud (") + result.status().error_msg() + ")");
    cloud_ = std::move(result).value();
    if (cloud_->num_points() != n)
      fail("Draco point cloud holds " + std::to_string(cloud_->num_points()) + " points, expected " +
           std::to_string(n));
    if (cloud_->num_attributes() != 1) fail("expected exactly one Draco attribute");
    const draco::PointAttribute* att = cloud_->attribute(0);
    if (att == nullptr || att->buffer() == nullptr || att->data_type() != draco::DT_INT32 ||
        att->num_components() != components)
      fail("expected a " + std::to_string(components) + "-component int32 Draco attribute");
    if (n == 0) return;
    const std::size_t stride = components * sizeof(std::int32_t);
    if (att->is_mapping_identity() && att->byte_stride() == static_cast<std::int64_t>(stride) &&
        att->byte_offset() == 0 && att->size() == n && att->buffer()->data_size() >= n * stride) {
      values_ = reinterpret_cast<const std::int32_t*>(att->buffer()->data());
      return;
    }
    if (!att->is_mapping_identity() && att->indices_map_size() < n)
      fail("Draco attribute maps fewer values than points");
    copy_.resize(n * components);
    for (std::size_t i = 0; i < n; ++i) {
      const draco::AttributeValueIndex index = att->mapped_index(draco::PointIndex(static_cast<std::uint32_t>(i)));
      std::array<std::int32_t, 3> v3{};
      std::array<std::int32_t, 1> v1{};
      const bool ok =
          components == 1 ? att->GetValue<std::int32_t, 1>(index, &v1) : att->GetValue<std::int32_t, 3>(index, &v3);
      if (!ok) fail("Draco attribute value " + std::to_string(i) + " lies outside its buffer");
      std::memcpy(copy_.data() + i * components, components == 1 ? v1.data() : v3.data(), stride);
    }
    values_ = copy_.data();
  }
  const std::int32_t* values() const { return values_; }

 private:
  std::unique_ptr<draco::PointCloud> cloud_;
  std::vector<std::int32_t> copy_;
  const std::int32_t* values_ = nullptr;
};

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

struct ResidualChunk::Clouds {
  std::optional<DecodedCloud> symbols, escapes;
};

ResidualChunk::ResidualChunk(const ChunkBytes& chunk, std::uint32_t joint_bits, std::uint64_t points,
                             const std::string& file)
    : clouds_(std::make_unique<Clouds>()), bits_(joint_bits), mask_((1u << joint_bits) - 1) {
  const std::size_t n = points;
  symbol_ =
      clouds_->symbols.emplace(chunk.symbols, n, 1, "position chunk symbols", file, chunk.symbols_offset).values();
  if (n == 0) return;
  // Symbols above 2^3t name no triplet; 0 takes the next escape.
  const std::uint32_t largest = 1u << 3 * joint_bits;
  std::size_t escaped = 0;
  bool in_range = true;
  for (std::size_t i = 0; i < n; ++i) {
    escaped += symbol_[i] == 0;
    in_range &= static_cast<std::uint32_t>(symbol_[i]) <= largest;
  }
  if (!in_range) fail_input(file, chunk.symbols_offset, "position chunk symbols: a symbol lies outside [0, 2^3t]");
  if (escaped == 0 && !chunk.escapes.empty())
    fail_input(file, chunk.escapes_offset, "position chunk escapes: present although no point escapes");
  if (escaped > 0 && chunk.escapes.empty())
    fail_input(file, chunk.escapes_offset,
               "position chunk escapes: missing for " + std::to_string(escaped) + " escaped points");
  if (escaped > 0)
    escape_ = clouds_->escapes.emplace(chunk.escapes, escaped, 3, "position chunk escapes", file, chunk.escapes_offset)
                  .values();
}

ResidualChunk::~ResidualChunk() = default;

void decode_residual_chunk(const ChunkBytes& chunk, std::uint32_t joint_bits, std::span<std::int32_t> xyz,
                           const std::string& file) {
  ResidualChunk residuals(chunk, joint_bits, xyz.size() / 3, file);
  for (std::size_t i = 0; i + 3 <= xyz.size(); i += 3) residuals.next(xyz.data() + i);
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
