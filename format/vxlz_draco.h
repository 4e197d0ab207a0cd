// The Draco side of the .vxlz package (spec/vxlz-package-v1.md §5.3): one chunk of prediction residuals
// (int32 triplets, in point order) as one Draco point cloud, sequentially encoded so that the point order
// survives, without deduplication and without Draco quantisation (the residuals are coded losslessly).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace vxl {

// Encodes 3 * n residuals (x, y, z interleaved; n < 2^31). Throws vxl::Error (Output) if Draco fails.
std::vector<std::uint8_t> encode_residual_chunk(std::span<const std::int32_t> xyz);

// Decodes one chunk into `xyz` (3 * n values for the n points the chunk must hold). Throws vxl::Error
// (Input) naming `file` and `offset` (the chunk's position in the package) unless the buffer is a Draco
// point cloud of exactly n points with one 3-component int32 attribute.
void decode_residual_chunk(std::span<const std::uint8_t> buffer, std::span<std::int32_t> xyz, const std::string& file,
                           std::uint64_t offset);

// For the benchmark's baseline only (not used by the package): the size of `xyz` (3 * n floats) as one
// Draco point cloud with Draco's own quantisation (`bits` over the cube at `origin` with edge `range`)
// and its own prediction, sequentially encoded — what the package's predictor is compared against.
std::size_t draco_native_size(std::span<const float> xyz, std::uint32_t bits, const float origin[3], float range);

}  // namespace vxl
