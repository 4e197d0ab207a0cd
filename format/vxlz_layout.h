// On-disk structures of the .vxlz package, version 2.3 (spec/vxlz-package-v2.md; section numbers below
// point into it). The header and the section table entries have the .vxl layout (FileHeader,
// SectionEntry from vxl_layout.h) with another magic; the payloads follow each other without padding.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "format/vxl_layout.h"

namespace vxl {

inline constexpr std::array<std::uint8_t, 8> kVxlzMagic = {0x89, 'V', 'X', 'Z', '\r', '\n', 0x1A, '\n'};
inline constexpr std::uint16_t kVxlzVersionMajor = 2;  // 1.0 coded residual triplets with no joint symbols
// A writer writes minor 4 when the package ships its points level by level (§5.1) with a checksum per chunk (CHKS),
// minor 3 for the level order without them (older writers), else 2 when it holds values
// per group (§4.8), else 1 when it holds value sets (§4.7), else 0 (§10: the lowest version that holds what it
// writes).
inline constexpr std::uint16_t kVxlzVersionMinor = 1;
inline constexpr std::uint16_t kVxlzVersionMinorGroupValues = 2;
inline constexpr std::uint16_t kVxlzVersionMinorLevelOrder = 3;
// §2.2: CHKS, a checksum per position chunk, written with the level order, so that a prefix's chunks are checked
// before a viewer shows the level they hold.
inline constexpr std::uint16_t kVxlzVersionMinorChunkChecksums = 4;
inline constexpr std::uint32_t kVxlzMaxSections = 32;
inline constexpr std::uint32_t kVxlzMinBits = 11;
inline constexpr std::uint32_t kVxlzMaxBits = 16;
inline constexpr std::uint32_t kVxlzDefaultBits = 14;
inline constexpr std::uint32_t kVxlzPredictorLinear = 1;  // §5.2, the points in streamline order
// §5.2 over the points in level order (§5.1): the coarsest level's streamlines first. An older reader refuses the
// predictor as unsupported instead of decoding the points into the wrong streamlines.
inline constexpr std::uint32_t kVxlzPredictorLinearLevelOrder = 2;
inline constexpr std::uint64_t kVxlzDefaultChunkPoints = 1u << 18;
inline constexpr std::uint64_t kVxlzMaxChunkPoints = (1u << 31) - 1;  // Draco point indices are 32-bit
inline constexpr std::uint32_t kVxlzMinJointBits = 1;                 // §5.3: zigzagged residuals of up to t bits per
inline constexpr std::uint32_t kVxlzMaxJointBits = 5;                 // component share one symbol (at most 2^15)

// §3
struct PackSection {
  std::uint32_t quantization_bits;
  std::uint32_t predictor;
  double quant_origin[3];
  double quantum;
  double range;
  std::uint64_t point_count;  // shipped points
  std::uint64_t chunk_points;
  std::uint64_t chunk_count;
  double error_bound;
  double max_error;           // informative
  double rms_error;           // informative
  std::uint32_t joint_bits;   // t of the joint symbols (§5.3)
  std::uint32_t level_count;  // Λ of the level order (§5.1), 2..8, with predictor 2; else 0
  std::uint8_t reserved[24];
};
static_assert(sizeof(PackSection) == 128);
static_assert(offsetof(PackSection, quant_origin) == 8);
static_assert(offsetof(PackSection, point_count) == 48);
static_assert(offsetof(PackSection, error_bound) == 72);
static_assert(offsetof(PackSection, joint_bits) == 96);
static_assert(offsetof(PackSection, level_count) == 100);
static_assert(offsetof(PackSection, reserved) == 104);

}  // namespace vxl
