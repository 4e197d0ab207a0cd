// The text header MRtrix puts in front of its track files (TCK, "mrtrix tracks"), track scalar files
// (TSF, "mrtrix track scalars") and images (.mif/.mih, "mrtrix image"): a magic line, "key: value" lines
// (keys may repeat; a line without a colon continues the previous value), "END". Required: "datatype" and
// "file: . OFFSET" (data in the same file, after the header); an image's header (.mih) may name another
// file instead, "file: NAME [OFFSET]". One parser for all, and for a whole file as for its first bytes.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <string>
#include <type_traits>

#include <nlohmann/json.hpp>

namespace vxl {

struct MrtrixHeader {
  nlohmann::json fields = nlohmann::json::object();  // key -> array of values (keys may repeat)
  std::string datatype;
  std::uint64_t data_offset = 0;
  std::string data_file = ".";            // "." is this file (only images name another)
  std::optional<std::string> count_text;  // "count" as the header spells it (warnings quote it)
  std::optional<std::uint64_t> count;  // count_text, when it is a decimal number (it may be stale: the data is trusted)
  // The last value of `key`, if present.
  std::optional<std::string> last(const char* key) const;
};

// What is being parsed: the magic line, and the name used in messages ("TCK", "TSF").
struct MrtrixFileKind {
  const char* magic;
  const char* name;
  bool data_elsewhere = false;  // "file:" may name another file
};
inline constexpr MrtrixFileKind kTckFile{"mrtrix tracks", "TCK"};
inline constexpr MrtrixFileKind kTsfFile{"mrtrix track scalars", "TSF"};
inline constexpr MrtrixFileKind kImageFile{"mrtrix image", "MRtrix image", true};

// The warning about a header "count" that is no number or not `streamlines` (the data is trusted), if any.
std::optional<std::string> count_warning(const MrtrixHeader& h, std::uint64_t streamlines);

// Parses the header at the start of `bytes`, the first bytes of a file of `file_size` bytes. Returns
// nullopt when `bytes` is shorter than the file and holds no END line yet (read more and call again);
// throws vxl::Error (Input / Unsupported) naming `path` and the byte offset where known.
std::optional<MrtrixHeader> parse_mrtrix_header(const std::string& path, std::span<const std::uint8_t> bytes,
                                                std::uint64_t file_size, const MrtrixFileKind& kind);

// The same for a whole file in memory (never nullopt).
inline MrtrixHeader parse_mrtrix_header(const std::string& path, std::span<const std::uint8_t> whole_file,
                                        const MrtrixFileKind& kind) {
  return *parse_mrtrix_header(path, whole_file, whole_file.size(), kind);
}

// The number types of the data that follows the header ("datatype:"): Float32/Float64, little- or
// big-endian. The only ones MRtrix writes to track and track scalar files.
enum class MrtrixDatatype { kFloat32LE, kFloat32BE, kFloat64LE, kFloat64BE };

// `datatype` as one of them; any other throws vxl::Error (Unsupported) naming `path`:
// "TCK datatype 'X' (expected Float32LE, Float32BE, Float64LE or Float64BE)" (kind.name for "TCK").
MrtrixDatatype mrtrix_datatype(const std::string& path, const std::string& datatype, const MrtrixFileKind& kind);

// Returns f.template operator()<Real, kBigEndian>() for `type`: Real is float or double, kBigEndian
// true for the BE types (as load_mrtrix_value takes them).
template <typename F>
decltype(auto) visit_mrtrix_datatype(MrtrixDatatype type, F&& f) {
  switch (type) {
    case MrtrixDatatype::kFloat32LE: return f.template operator()<float, false>();
    case MrtrixDatatype::kFloat32BE: return f.template operator()<float, true>();
    case MrtrixDatatype::kFloat64LE: return f.template operator()<double, false>();
    case MrtrixDatatype::kFloat64BE: break;
  }
  return f.template operator()<double, true>();
}

// One value of the data that follows the header: Float32/Float64, little- or big-endian (the datatype's
// LE/BE suffix), at any alignment.
template <typename Real, bool kBigEndian>
Real load_mrtrix_value(const std::uint8_t* p) {
  using Bits = std::conditional_t<sizeof(Real) == 4, std::uint32_t, std::uint64_t>;
  Bits bits;
  std::memcpy(&bits, p, sizeof bits);
  if constexpr (kBigEndian) {
    if constexpr (sizeof(Bits) == 4)
      bits = __builtin_bswap32(bits);
    else
      bits = __builtin_bswap64(bits);
  }
  return std::bit_cast<Real>(bits);
}

}  // namespace vxl
