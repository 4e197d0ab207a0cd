#include "format/vxlz_draco.h"

#include <array>
#include <cstring>
#include <optional>

#include <draco/compression/point_cloud/point_cloud_sequential_decoder.h>
#include <draco/point_cloud/point_cloud.h>

#include "format/base/error.h"

namespace vxl {

// A decoded cloud of exactly n points with one int32 attribute of `components` components, its values
// dense in point order: read in place from Draco's buffer when it is laid out so (sequential decoding
// always is), else copied point by point through the attribute's mapping. ResidualChunk, declared in the
// header, holds two.
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
    // The sequential decoder itself (the header said so above), not draco::Decoder, which links every mesh
    // and k-d tree decoder as well.
    cloud_ = std::make_unique<draco::PointCloud>();
    draco::PointCloudSequentialDecoder decoder;
    const draco::Status status = decoder.Decode(draco::DecoderOptions(), &buffer, cloud_.get());
    if (!status.ok()) fail(std::string("not a Draco point cloud (") + status.error_msg() + ")");
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

}  // namespace vxl
