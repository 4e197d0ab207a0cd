// TRK reader (TrackVis .trk, versions 1 and 2, either byte order, optionally gzip-compressed).
//
// Coordinate convention: TRK stores "voxmm" points, i.e. millimetres measured from the corner of voxel
// (0,0,0) along the image axes. We map them to RAS mm exactly as nibabel's TrkFile does (nibabel is the
// reference implementation, and our output must equal nibabel.streamlines.load(path).streamlines):
//
//   voxel = p / voxel_size - 0.5                       (voxmm -> voxel index, voxel centres at integers)
//   voxel' = flip/permute(voxel) where voxel_order disagrees with the orientation of vox_to_ras
//   ras   = vox_to_ras * voxel'
//
// vox_to_ras with element [3][3] == 0 (always so for version 1, which has no matrix) means "not
// recorded": nibabel then uses the identity, and so do we (with a warning). An empty voxel_order means
// TrackVis's default, LPS. The whole affine is composed in double and each point is rounded once to
// float32 (nibabel composes in double but applies a float32 copy, so we agree to float32 rounding).
//
// Layout: 1000-byte header; then per streamline: int32 n, n * (3 + n_scalars) float32,
// n_properties float32. hdr_size (int32 at byte 996) is 1000 in the file's byte order, which is how
// a big-endian file is recognised. Scalars become per-point value sets and properties per-streamline value
// sets, named from the header's name slots (a slot "name\0N", nibabel's way of naming N values, gives
// name[0] ... name[N-1]).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "converter/readers/gzip_bytes.h"
#include "converter/readers/latin1.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/regular_file.h"
#include "converter/readers/trk_header.h"
#include "format/base/checksum.h"
#include "format/base/error.h"
#include "format/base/mapped_file.h"

namespace vxl {
namespace {

using namespace trk;

// Reads numbers of the file's byte order from an in-memory buffer. Callers bounds-check first; loads
// go through memcpy because nothing in a TRK file is aligned beyond 4 bytes and the header-relative
// offsets of records are arbitrary.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size, bool big_endian)
      : data_(data), size_(size), swap_(big_endian != (std::endian::native == std::endian::big)) {}

  std::size_t size() const { return size_; }
  const std::uint8_t* data() const { return data_; }

  std::uint32_t u32(std::size_t off) const {
    std::uint32_t v;
    std::memcpy(&v, data_ + off, 4);
    return swap_ ? swap32(v) : v;
  }
  std::int32_t i32(std::size_t off) const { return static_cast<std::int32_t>(u32(off)); }
  float f32(std::size_t off) const { return std::bit_cast<float>(u32(off)); }
  std::int16_t i16(std::size_t off) const {
    std::uint16_t v;
    std::memcpy(&v, data_ + off, 2);
    if (swap_) v = static_cast<std::uint16_t>((v >> 8) | (v << 8));
    return static_cast<std::int16_t>(v);
  }

  static std::uint32_t swap32(std::uint32_t v) {
    return (v >> 24) | ((v >> 8) & 0xFF00u) | ((v << 8) & 0xFF0000u) | (v << 24);
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  bool swap_;
};

// Header strings are NUL-padded Latin-1; JSON needs UTF-8.
std::string latin1_field(const std::uint8_t* p, std::size_t max_len) {
  std::size_t n = 0;
  while (n < max_len && p[n] != 0) ++n;
  return latin1_to_utf8({reinterpret_cast<const char*>(p), n});
}

std::string trim_right(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.pop_back();
  return s;
}

// Names of scalars/properties: up to 10 slots of 20 bytes. nibabel may encode a count after the name
// ("name\0" + digits) for multi-valued entries; the name is what precedes the first NUL.
nlohmann::json slot_names(const std::uint8_t* p) {
  nlohmann::json names = nlohmann::json::array();
  for (int i = 0; i < 10; ++i) {
    std::string name = trim_right(latin1_field(p + 20 * i, 20));
    if (!name.empty()) names.push_back(name);
  }
  return names;
}

// One name per value: the slots' names expanded by their counts ("colors\03" -> colors[0..2]), padded
// with "<fallback>_k" or cut to `count` (with a warning) when the slots disagree with n_scalars/n_properties.
std::vector<std::string> value_names(const std::uint8_t* slots, int count, const char* fallback,
                                     std::vector<std::string>& warnings) {
  std::vector<std::string> names;
  for (int i = 0; i < 10 && static_cast<int>(names.size()) < count; ++i) {
    const std::uint8_t* p = slots + 20 * i;
    std::size_t n = 0;
    while (n < 20 && p[n] != 0) ++n;
    const std::string name = trim_right(latin1_to_utf8({reinterpret_cast<const char*>(p), n}));
    if (name.empty()) continue;
    int multiple = 1;
    if (n + 1 < 20 && p[n + 1] >= '1' && p[n + 1] <= '9') {
      multiple = 0;
      for (std::size_t k = n + 1; k < 20 && p[k] >= '0' && p[k] <= '9'; ++k) multiple = multiple * 10 + (p[k] - '0');
    }
    if (multiple == 1)
      names.push_back(name);
    else
      for (int k = 0; k < multiple; ++k) names.push_back(name + "[" + std::to_string(k) + "]");
  }
  if (static_cast<int>(names.size()) != count)
    warnings.push_back(std::string("the header names ") + std::to_string(names.size()) + " " + fallback +
                       " values but holds " + std::to_string(count) + "; unnamed ones are called " + fallback + "_<k>");
  names.resize(count);
  for (int k = 0; k < count; ++k)
    if (names[k].empty()) names[k] = std::string(fallback) + "_" + std::to_string(k);
  return names;
}

Mat4 identity4() {
  Mat4 m{};
  for (int i = 0; i < 4; ++i) m[i][i] = 1.0;
  return m;
}

Mat4 mul(const Mat4& a, const Mat4& b) {
  Mat4 r{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) r[i][j] += a[i][k] * b[k][j];
  return r;
}

using Mat3 = std::array<std::array<double, 3>, 3>;

double det3(const Mat3& m) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

// Transposed inverse by cofactors (the caller guarantees a non-singular matrix).
Mat3 inverse_transpose3(const Mat3& m) {
  const double d = det3(m);
  Mat3 c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      c[i][j] = (m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]) / d;  // cofactor(i,j) / det
    }
  return c;  // inverse = cofactor^T / det, so its transpose is cofactor / det
}

// An axis code such as 'L': which RAS axis (0 = x/LR, 1 = y/PA, 2 = z/IS) and which direction.
struct AxisCode {
  int axis;
  int sign;  // +1 towards R/A/S, -1 towards L/P/I
};
using Orientation = std::array<AxisCode, 3>;

std::string orientation_name(const Orientation& o) {
  static const char* kLetters[3][2] = {{"L", "R"}, {"P", "A"}, {"I", "S"}};
  std::string s;
  for (const auto& a : o) s += kLetters[a.axis][a.sign > 0 ? 1 : 0];
  return s;
}

std::optional<Orientation> parse_orientation(const std::string& code) {
  if (code.size() != 3) return std::nullopt;
  Orientation o{};
  bool seen[3] = {false, false, false};
  for (int i = 0; i < 3; ++i) {
    switch (code[i]) {
      case 'R': o[i] = {0, +1}; break;
      case 'L': o[i] = {0, -1}; break;
      case 'A': o[i] = {1, +1}; break;
      case 'P': o[i] = {1, -1}; break;
      case 'S': o[i] = {2, +1}; break;
      case 'I': o[i] = {2, -1}; break;
      default: return std::nullopt;
    }
    if (seen[o[i].axis]) return std::nullopt;  // e.g. "LRS": an axis twice is no orientation
    seen[o[i].axis] = true;
  }
  return o;
}

// Orientation of the voxel axes of an affine, as nibabel's aff2axcodes computes it: normalise the
// columns, take the closest rotation (orthogonal polar factor, found here by Newton's iteration
// X <- (X + X^-T) / 2 instead of an SVD), then give each voxel axis, in order, the world axis its column
// points along most, never reusing a world axis. Returns nullopt for a singular matrix, for which
// nibabel refuses the file.
std::optional<Orientation> affine_orientation(const Mat4& a) {
  Mat3 rs{};
  for (int j = 0; j < 3; ++j) {
    double norm = 0;
    for (int i = 0; i < 3; ++i) norm += a[i][j] * a[i][j];
    norm = std::sqrt(norm);
    if (norm == 0) norm = 1;  // a zero column stays zero (and makes the matrix singular)
    for (int i = 0; i < 3; ++i) rs[i][j] = a[i][j] / norm;
  }
  if (!std::isfinite(det3(rs)) || std::fabs(det3(rs)) < 1e-12) return std::nullopt;
  Mat3 r = rs;
  for (int iter = 0; iter < 100; ++iter) {
    const Mat3 it = inverse_transpose3(r);
    double change = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double next = 0.5 * (r[i][j] + it[i][j]);
        change = std::max(change, std::fabs(next - r[i][j]));
        r[i][j] = next;
      }
    if (change < 1e-15) break;
  }
  Orientation o{};
  for (int in_ax = 0; in_ax < 3; ++in_ax) {
    int out_ax = 0;
    double best = -1;
    for (int i = 0; i < 3; ++i)
      if (std::fabs(r[i][in_ax]) > best) {  // strict '>' keeps the first of equal maxima, like argmax
        best = std::fabs(r[i][in_ax]);
        out_ax = i;
      }
    if (best < 1e-8) return std::nullopt;
    o[in_ax] = {out_ax, r[out_ax][in_ax] < 0 ? -1 : +1};
    for (int j = 0; j < 3; ++j) r[out_ax][j] = 0;  // this world axis is taken
  }
  return o;
}

// The voxel -> voxel affine that re-expresses indices given in the header's voxel_order in the
// orientation of vox_to_ras (nibabel: inv_ornt_aff(ornt_transform(header_ornt, affine_ornt), dim)).
// A flipped axis maps i -> (dim - 1) - i, i.e. it mirrors about the centre of the grid.
Mat4 reorient(const Orientation& header, const Orientation& affine, const std::array<double, 3>& dim) {
  Mat4 m{};
  m[3][3] = 1;
  for (int i = 0; i < 3; ++i) {
    int target = 0;
    for (int j = 0; j < 3; ++j)
      if (affine[j].axis == header[i].axis) target = j;
    const double flip = header[i].sign == affine[target].sign ? 1.0 : -1.0;
    const double centre = -(dim[i] - 1.0) / 2.0;
    m[i][target] = flip;
    m[i][3] = flip * centre - centre;
  }
  return m;
}

// The header fields the reader uses, decoded in the file's byte order (stage 1 of read_trk).
struct TrkHeader {
  std::array<std::uint8_t, kHeaderSize> bytes{};
  bool big_endian = false;
  std::int32_t version = 0, n_count = 0;
  int n_scalars = 0, n_properties = 0;
  std::array<double, 3> dim{}, voxel_size{};
  Mat4 recorded{};  // vox_to_ras as stored (zero in version 1)
  bool vox_to_ras_recorded = false;
  Bytes fields() const { return Bytes(bytes.data(), bytes.size(), big_endian); }
};

// Reports a problem at an offset of the TRK stream (the decompressed one for a .gz file).
using FailAt = std::function<void(std::uint64_t, const std::string&)>;

TrkHeader read_header(GzipBytes& stream, const std::string& path, std::vector<std::string>& warnings,
                      const FailAt& fail_at) {
  TrkHeader h;
  if (const std::uint8_t* p = stream.take(kHeaderSize)) {
    std::memcpy(h.bytes.data(), p, kHeaderSize);
  } else {
    const std::uint64_t size = stream.left();
    fail_at(size, "file ends after " + std::to_string(size) + " bytes, inside the 1000-byte TRK header");
  }
  const std::uint8_t* data = h.bytes.data();
  if (std::memcmp(data, "TRACK", 5) != 0) fail_at(0, "not a TrackVis file: expected the magic 'TRACK'");

  // hdr_size tells the byte order: 1000 as stored little-endian, or 1000 after swapping (big-endian).
  const Bytes le(data, kHeaderSize, false);
  if (le.i32(kOffHdrSize) != static_cast<std::int32_t>(kHeaderSize)) {
    if (Bytes(data, kHeaderSize, true).i32(kOffHdrSize) != static_cast<std::int32_t>(kHeaderSize))
      fail_at(kOffHdrSize, "hdr_size is " + std::to_string(le.i32(kOffHdrSize)) + " (little-endian) / " +
                               std::to_string(Bytes(data, kHeaderSize, true).i32(kOffHdrSize)) +
                               " (big-endian); expected 1000");
    h.big_endian = true;
  }
  const Bytes in = h.fields();

  h.version = in.i32(kOffVersion);
  if (h.version == 3) {
    // nibabel reads version 3 as version 2 with a warning; the layout is the same.
    warnings.push_back("TRK version 3 header read as version 2");
  } else if (h.version != 1 && h.version != 2) {
    fail_unsupported(path, "TRK version " + std::to_string(h.version) +
                               " (int32 at byte 992) is not supported; supported versions are 1 and 2");
  }
  for (int i = 0; i < 3; ++i) {
    h.dim[i] = in.i16(kOffDim + 2 * i);
    h.voxel_size[i] = in.f32(kOffVoxelSize + 4 * i);
  }
  h.n_scalars = in.i16(kOffNScalars);
  h.n_properties = in.i16(kOffNProperties);
  if (h.n_scalars < 0) fail_at(kOffNScalars, "negative n_scalars " + std::to_string(h.n_scalars));
  if (h.n_properties < 0) fail_at(kOffNProperties, "negative n_properties " + std::to_string(h.n_properties));
  h.n_count = in.i32(kOffNCount);
  // vox_to_ras exists from version 2 on; [3][3] == 0 is TrackVis's "not recorded".
  if (h.version >= 2)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) h.recorded[i][j] = in.f32(kOffVoxToRas + 4 * (4 * i + j));
  h.vox_to_ras_recorded = h.recorded[3][3] != 0;
  return h;
}

// Stage 2: the affine applied to the stored points (voxmm to RAS mm), as nibabel computes it.
Mat4 voxmm_to_ras(const TrkHeader& h, std::vector<std::string>& warnings, const FailAt& fail_at) {
  Mat4 vox_to_ras = h.recorded;
  if (!h.vox_to_ras_recorded) {
    vox_to_ras = identity4();
    warnings.push_back(h.version == 1 ? "TRK version 1 header has no vox_to_ras; using the identity (as nibabel)"
                                      : "vox_to_ras is not recorded (element [3][3] is 0); using the identity "
                                        "(as nibabel)");
  }
  std::string voxel_order = trim_right(latin1_field(h.bytes.data() + kOffVoxelOrder, 4));
  for (char& c : voxel_order)
    if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  if (voxel_order.empty()) {
    warnings.push_back("voxel_order is empty; assuming LPS, TrackVis's default (as nibabel)");
    voxel_order = "LPS";
  }
  const auto header_ornt = parse_orientation(voxel_order);
  if (!header_ornt)
    fail_at(kOffVoxelOrder, "voxel_order '" + voxel_order + "' is not an orientation code such as RAS or LPS");
  const auto affine_ornt = affine_orientation(vox_to_ras);
  if (!affine_ornt) fail_at(kOffVoxToRas, "vox_to_ras is singular: the voxel axis directions cannot be determined");

  for (double v : h.voxel_size)
    if (!(std::isfinite(v) && v != 0)) {
      // nibabel divides by zero here and returns NaN points. A header without voxel sizes (old files,
      // e.g. dipy's former tracks300.trk) carries no geometry at all; its points are world mm already.
      warnings.push_back("voxel_size is not recorded (zero); points are taken as RAS mm unchanged");
      return identity4();
    }
  if (orientation_name(*header_ornt) != orientation_name(*affine_ornt))
    warnings.push_back("voxel_order " + voxel_order + " disagrees with the orientation of vox_to_ras (" +
                       orientation_name(*affine_ornt) + "); voxel axes re-oriented as nibabel does");
  Mat4 scale = identity4();
  for (int i = 0; i < 3; ++i) scale[i][i] = 1.0 / h.voxel_size[i];
  Mat4 half_voxel = identity4();
  for (int i = 0; i < 3; ++i) half_voxel[i][3] = -0.5;
  return mul(vox_to_ras, mul(reorient(*header_ornt, *affine_ornt, h.dim), mul(half_voxel, scale)));
}

// Stage 3: the header as JSON provenance, with the affine actually applied.
nlohmann::json header_provenance(const TrkHeader& h, bool gz, const Mat4& applied_affine) {
  const Bytes in = h.fields();
  const std::uint8_t* data = h.bytes.data();
  nlohmann::json j;
  j["version"] = h.version;
  j["endianness"] = h.big_endian ? "big" : "little";
  if (gz) j["compression"] = "gzip";
  j["dim"] = {in.i16(kOffDim), in.i16(kOffDim + 2), in.i16(kOffDim + 4)};
  j["voxel_size"] = {h.voxel_size[0], h.voxel_size[1], h.voxel_size[2]};
  j["origin"] = {in.f32(kOffOrigin), in.f32(kOffOrigin + 4), in.f32(kOffOrigin + 8)};
  j["n_scalars"] = h.n_scalars;
  j["scalar_names"] = slot_names(data + kOffScalarNames);
  j["n_properties"] = h.n_properties;
  j["property_names"] = slot_names(data + kOffPropertyNames);
  if (h.version >= 2) {
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& row : h.recorded) rows.push_back(row);
    j["vox_to_ras"] = rows;
  } else {
    j["vox_to_ras"] = nullptr;
  }
  j["voxel_order"] = trim_right(latin1_field(data + kOffVoxelOrder, 4));
  nlohmann::json iop = nlohmann::json::array();
  for (int i = 0; i < 6; ++i) iop.push_back(in.f32(kOffImageOrient + 4 * i));
  j["image_orientation_patient"] = iop;
  static const char* kFlags[6] = {"invert_x", "invert_y", "invert_z", "swap_xy", "swap_yz", "swap_zx"};
  for (int i = 0; i < 6; ++i) j[kFlags[i]] = data[kOffInvertSwap + i];
  j["n_count"] = h.n_count;
  j["hdr_size"] = kHeaderSize;
  nlohmann::json applied = nlohmann::json::array();
  for (const auto& row : applied_affine) applied.push_back(row);
  j["voxmm_to_rasmm"] = applied;  // the affine actually applied to the stored points
  return j;
}

// Stage 4: the streamline records, mapped to RAS mm, with their scalars and properties.
void read_records(GzipBytes& stream, const TrkHeader& h, const Mat4& a, Tractogram& t, const FailAt& fail_at) {
  auto& warnings = t.source.warnings;
  // Sizes are computed in 64 bits: n < 2^31 and 3 + n_scalars < 2^15 cannot overflow.
  const std::uint64_t point_bytes = 4 * (3 + static_cast<std::uint64_t>(h.n_scalars));
  const std::uint64_t property_bytes = 4 * static_cast<std::uint64_t>(h.n_properties);
  if (const auto total = stream.size())
    t.positions.reserve(3 * ((*total - kHeaderSize) / point_bytes));  // an upper bound: no reallocation
  for (const std::string& name : value_names(h.bytes.data() + kOffScalarNames, h.n_scalars, "scalar", warnings))
    t.point_values.push_back({name, {}});
  for (const std::string& name : value_names(h.bytes.data() + kOffPropertyNames, h.n_properties, "property", warnings))
    t.streamline_values.push_back({name, {}});
  std::uint64_t count = 0;
  while (!stream.at_end()) {
    const std::uint64_t off = stream.offset();
    const std::uint8_t* q = stream.take(4);
    if (q == nullptr)
      fail_at(off, "truncated streamline record #" + std::to_string(count) + ": " + std::to_string(stream.left()) +
                       " bytes left where a 4-byte point count was expected");
    const std::int32_t n = Bytes(q, 4, h.big_endian).i32(0);
    if (n < 0)
      fail_at(off, "streamline #" + std::to_string(count) + " has a negative point count " + std::to_string(n));
    // TrackVis and nibabel never write a streamline without points; zeros where records should be are
    // what a damaged file or a decompression bomb holds, not empty streamlines.
    if (n == 0) fail_at(off, "streamline #" + std::to_string(count) + " has no points (point count 0)");
    const std::uint64_t need = static_cast<std::uint64_t>(n) * point_bytes + property_bytes;
    auto truncated = [&](std::uint64_t remain) {
      fail_at(off, "truncated streamline record #" + std::to_string(count) + ": " + std::to_string(n) +
                       " points need " + std::to_string(need) + " bytes after the count but only " +
                       std::to_string(remain) + " remain");
    };
    if (const auto total = stream.size(); total && need > *total - off - 4) truncated(*total - off - 4);
    for (std::int32_t i = 0; i < n; ++i) {
      const std::uint64_t p = stream.offset();
      q = stream.take(point_bytes);
      if (q == nullptr) truncated(p - off - 4 + stream.left());
      const Bytes pt(q, point_bytes, h.big_endian);
      const double x = pt.f32(0), y = pt.f32(4), z = pt.f32(8);
      for (int r = 0; r < 3; ++r) {
        const float v = voxmm_point_to_ras(a, r, x, y, z);
        if (!std::isfinite(v))
          fail_at(p, "streamline #" + std::to_string(count) + " point " + std::to_string(i) +
                         " is not finite after mapping to RAS mm");
        t.positions.push_back(v);
      }
      for (int k = 0; k < h.n_scalars; ++k) t.point_values[k].values.push_back(pt.f32(12 + 4 * k));
    }
    if (property_bytes > 0) {
      const std::uint64_t p = stream.offset();
      q = stream.take(property_bytes);
      if (q == nullptr) truncated(p - off - 4 + stream.left());
      const Bytes props(q, property_bytes, h.big_endian);
      for (int k = 0; k < h.n_properties; ++k) t.streamline_values[k].values.push_back(props.f32(4 * k));
    }
    t.offsets.push_back(t.point_count());
    ++count;
  }
  if (h.n_count != 0 && static_cast<std::uint64_t>(h.n_count) != count)
    warnings.push_back("header n_count is " + std::to_string(h.n_count) + " but the file holds " +
                       std::to_string(count) + " streamlines; the data is trusted");
}

}  // namespace

namespace trk {

Mat4 voxmm_to_rasmm(std::span<const std::uint8_t> header, const std::string& path, std::vector<std::string>& warnings) {
  GzipBytes stream(header);
  const FailAt fail_at = [&](std::uint64_t offset, const std::string& what) { fail_input(path, offset, what); };
  return voxmm_to_ras(read_header(stream, path, warnings, fail_at), warnings, fail_at);
}

std::optional<std::string> orientation_code(const Mat4& vox_to_ras) {
  const auto o = affine_orientation(vox_to_ras);
  return o ? std::optional<std::string>(orientation_name(*o)) : std::nullopt;
}

}  // namespace trk

// Header, affine, provenance, records: the four stages above.
Tractogram read_trk(const std::string& path) {
  Tractogram t;
  require_regular_file(path);
  const MappedFile file(path);
  t.source.path = path;
  t.source.format = "trk";
  t.source.dtype = "float32";
  t.source.bytes = file.size();
  t.source.xxh3_128 = xxh3_128_hex(file.data(), file.size());

  const bool gz = is_gzip(file.bytes());
  std::optional<GzipBytes> stream;
  if (gz)
    stream.emplace(path, file.bytes(), t.source.warnings, inflate_cap(file.size()),
                   "real tractograms compress about 1.2-3x");
  else
    stream.emplace(file.bytes());
  // Offsets in messages count bytes of the TRK stream, which for a .gz file is the decompressed one.
  const std::string where = gz ? " (offset in the decompressed data)" : "";
  const FailAt fail_at = [&](std::uint64_t offset, const std::string& what) { fail_input(path, offset, what + where); };

  const TrkHeader header = read_header(*stream, path, t.source.warnings, fail_at);
  const Mat4 affine = voxmm_to_ras(header, t.source.warnings, fail_at);
  t.source.header = header_provenance(header, gz, affine);
  if (header.vox_to_ras_recorded) {
    std::array<double, 16> m{};
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) m[4 * i + j] = header.recorded[i][j];
    t.source.vox_to_ras = m;
  }
  read_records(*stream, header, affine, t, fail_at);
  return t;
}

}  // namespace vxl
