// The TrackVis .trk header as the reader and the writer share it: the field offsets of the 1000-byte
// header, and the geometry the reader derives from it, so that the writer maps points with the exact
// inverse of what the reader applies.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace vxl::trk {

inline constexpr std::size_t kHeaderSize = 1000;

// Byte offsets of the header fields (TrackVis header layout).
inline constexpr std::size_t kOffDim = 6;              // int16[3]
inline constexpr std::size_t kOffVoxelSize = 12;       // float32[3]
inline constexpr std::size_t kOffOrigin = 24;          // float32[3] (unused by TrackVis and nibabel)
inline constexpr std::size_t kOffNScalars = 36;        // int16
inline constexpr std::size_t kOffScalarNames = 38;     // char[10][20]
inline constexpr std::size_t kOffNProperties = 238;    // int16
inline constexpr std::size_t kOffPropertyNames = 240;  // char[10][20]
inline constexpr std::size_t kOffVoxToRas = 440;       // float32[4][4], row-major (version 2 only)
inline constexpr std::size_t kOffVoxelOrder = 948;     // char[4]
inline constexpr std::size_t kOffImageOrient = 956;    // float32[6]
inline constexpr std::size_t kOffInvertSwap = 982;     // uint8 invert_x, invert_y, invert_z, swap_xy, swap_yz, swap_zx
inline constexpr std::size_t kOffNCount = 988;         // int32
inline constexpr std::size_t kOffVersion = 992;        // int32
inline constexpr std::size_t kOffHdrSize = 996;        // int32
inline constexpr int kNameSlots = 10, kNameSlotBytes = 20;

using Mat4 = std::array<std::array<double, 4>, 4>;

// The affine read_trk applies to the stored (voxmm) points of a file with this header, to RAS mm; the
// warnings it gives on the way. Throws vxl::Error naming `path` as read_trk does for a bad header.
Mat4 voxmm_to_rasmm(std::span<const std::uint8_t> header, const std::string& path, std::vector<std::string>& warnings);

// One RAS coordinate (row r) of a stored point, as read_trk computes it: the affine in double, left to right,
// rounded once to float32. The exporter inverts this very arithmetic.
inline float voxmm_point_to_ras(const Mat4& a, int r, double x, double y, double z) {
  return static_cast<float>(a[r][0] * x + a[r][1] * y + a[r][2] * z + a[r][3]);
}

// The orientation of an affine's voxel axes as nibabel's aff2axcodes gives it ("RAS", "LPS", …);
// nullopt for a singular one.
std::optional<std::string> orientation_code(const Mat4& vox_to_ras);

}  // namespace vxl::trk
