// The Draco side of the .vxlz package (spec/vxlz-package-v2.md §5.3): one chunk of prediction residuals
// (int32 triplets, in point order) as two Draco point clouds, sequentially encoded so that the point
// order survives, without deduplication and without Draco quantisation (integers are coded losslessly):
// a cloud of one joint symbol per point for the small residuals, and a cloud of the residual triplets
// that do not fit a symbol (escapes).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "format/vxlz_layout.h"

namespace vxl {

// One chunk's Draco buffers. `escapes` is empty when no point escapes.
struct EncodedChunk {
  std::vector<std::uint8_t> symbols, escapes;
};

// Where a chunk's buffers are, for decoding and for error messages.
struct ChunkBytes {
  std::span<const std::uint8_t> symbols, escapes;
  std::uint64_t symbols_offset = 0, escapes_offset = 0;  // file offsets
};

// The joint symbol of a residual triplet for joint_bits t (spec §5.3): 1 + z0 + z1·2^t + z2·2^2t with
// z the zigzag of each component, or 0 (escape) when a z does not fit in t bits.
std::uint32_t joint_symbol(const std::int32_t r[3], std::uint32_t joint_bits);

// Encodes 3 * n residuals (x, y, z interleaved; n < 2^31) with joint_bits in [kVxlzMinJointBits,
// kVxlzMaxJointBits]. Throws vxl::Error (Output) if Draco fails.
EncodedChunk encode_residual_chunk(std::span<const std::int32_t> xyz, std::uint32_t joint_bits);

// One decoded chunk, read point by point, so that a caller places the points without a buffer of
// residuals in between. The constructor decodes and checks both clouds: it throws vxl::Error (Input)
// naming `file` and the offset of the offending buffer unless the symbol buffer is a Draco point cloud of
// exactly `points` points with one 1-component int32 attribute whose values lie in [0, 2^3t], and the
// escape buffer is empty when no symbol is 0 and otherwise a cloud of exactly that many points with one
// 3-component int32 attribute. Safe for untrusted bytes; after it, next() needs no checks.
class ResidualChunk {
 public:
  ResidualChunk(const ChunkBytes& chunk, std::uint32_t joint_bits, std::uint64_t points, const std::string& file);
  ~ResidualChunk();
  ResidualChunk(const ResidualChunk&) = delete;
  ResidualChunk& operator=(const ResidualChunk&) = delete;

  // The next point's residual triplet; call it once per point, in order.
  void next(std::int32_t r[3]) {
    const std::uint32_t s = static_cast<std::uint32_t>(*symbol_++);
    if (s == 0) {
      r[0] = escape_[0], r[1] = escape_[1], r[2] = escape_[2];
      escape_ += 3;
      return;
    }
    const std::uint32_t u = s - 1;
    r[0] = unzigzag(u & mask_);
    r[1] = unzigzag((u >> bits_) & mask_);
    r[2] = unzigzag(u >> 2 * bits_);
  }

 private:
  static std::int32_t unzigzag(std::uint32_t z) { return static_cast<std::int32_t>((z >> 1) ^ (0u - (z & 1))); }
  struct Clouds;  // the decoded Draco point clouds, which own the values read below
  std::unique_ptr<Clouds> clouds_;
  const std::int32_t* symbol_ = nullptr;
  const std::int32_t* escape_ = nullptr;
  std::uint32_t bits_ = 0, mask_ = 0;
};

// Decodes one chunk into `xyz` (3 * n values for the n points the chunk must hold), with the checks of
// ResidualChunk.
void decode_residual_chunk(const ChunkBytes& chunk, std::uint32_t joint_bits, std::span<std::int32_t> xyz,
                           const std::string& file);

// For the benchmark's baseline only (not used by the package): the size of `xyz` (3 * n floats) as one
// Draco point cloud with Draco's own quantisation (`bits` over the cube at `origin` with edge `range`)
// and its own prediction, sequentially encoded — what the package's predictor is compared against.
std::size_t draco_native_size(std::span<const float> xyz, std::uint32_t bits, const float origin[3], float range);

}  // namespace vxl
