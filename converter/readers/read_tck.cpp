// TCK reader (MRtrix3 tracks file).
//
// Coordinate convention: TCK stores world coordinates, RAS mm, as-is; we convert to float32 (exact for
// Float32 files, rounded to nearest for Float64 files: spec §8).
//
// Layout: text header "mrtrix tracks" / "key: value" lines (keys may repeat) / "END"; the data starts at
// the byte offset in "file: . OFFSET". Data: xyz triplets; a triplet whose x is NaN ends a streamline, one
// whose x is Inf ends the file. Like MRtrix we tolerate a missing Inf terminator at EOF, and trust the data
// over a stale "count".
#include <bit>
#include <cmath>
#include <cstring>
#include <string_view>

#include "checksum.h"
#include "error.h"
#include "mapped_file.h"
#include "read_tractogram.h"

namespace vxl {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  return s;
}

struct TckHeader {
  nlohmann::json fields = nlohmann::json::object();  // key -> array of values (keys may repeat)
  std::string datatype;
  std::uint64_t data_offset = 0;
  std::optional<std::uint64_t> count;
};

TckHeader parse_header(const std::string& path, std::span<const std::uint8_t> bytes) {
  TckHeader h;
  std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  std::size_t pos = 0;
  auto next_line = [&](std::string_view& line) {
    if (pos >= text.size()) return false;
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    line = text.substr(pos, end - pos);
    pos = end + 1;
    return true;
  };
  std::string_view line;
  if (!next_line(line) || trim(line) != "mrtrix tracks")
    fail_input(path, 0, "expected the TCK magic line 'mrtrix tracks'");
  bool ended = false;
  std::string last_key;
  while (true) {
    std::size_t line_start = pos;
    if (!next_line(line)) break;
    std::string_view t = trim(line);
    if (t == "END") {
      ended = true;
      break;
    }
    if (t.empty()) continue;
    std::size_t colon = t.find(':');
    if (colon == std::string_view::npos) {
      // A line without a colon continues the previous value (seen in real command_history fields).
      if (last_key.empty()) fail_input(path, line_start, "expected a 'key: value' header line or 'END'");
      auto& values = h.fields[last_key];
      values.back() = values.back().get<std::string>() + "\n" + std::string(t);
      continue;
    }
    std::string key(trim(t.substr(0, colon)));
    last_key = key;
    std::string value(trim(t.substr(colon + 1)));
    h.fields[key].push_back(value);
  }
  if (!ended) fail_input(path, bytes.size(), "TCK header has no 'END' line");

  auto single = [&](const char* key) -> std::string {
    if (!h.fields.contains(key)) fail_input(path, std::nullopt, std::string("TCK header lacks '") + key + ":'");
    return h.fields[key].back().get<std::string>();
  };
  h.datatype = single("datatype");
  std::string file = single("file");
  if (file.size() < 2 || file[0] != '.' || file[1] != ' ')
    fail_unsupported(path, "TCK 'file:' must be '. OFFSET' (data in the same file); got '" + file + "'");
  try {
    std::size_t used = 0;
    long long off = std::stoll(file.substr(2), &used);
    if (off < 0) throw std::out_of_range("negative");
    h.data_offset = static_cast<std::uint64_t>(off);
  } catch (const std::exception&) {
    fail_input(path, std::nullopt, "TCK 'file:' offset is not a number: '" + file + "'");
  }
  if (h.data_offset < pos) fail_input(path, h.data_offset, "TCK data offset points inside the header");
  if (h.data_offset > bytes.size())
    fail_input(path, h.data_offset, "TCK data offset is past the end of the file (" + std::to_string(bytes.size()) + " bytes)");
  if (h.fields.contains("count")) {
    try {
      h.count = std::stoull(h.fields["count"].back().get<std::string>());
    } catch (const std::exception&) {
      // a malformed count is as good as a stale one: we trust the data
    }
  }
  return h;
}

template <typename Real, bool kBigEndian>
Real load(const std::uint8_t* p) {
  using Bits = std::conditional_t<sizeof(Real) == 4, std::uint32_t, std::uint64_t>;
  Bits bits;
  std::memcpy(&bits, p, sizeof bits);
  if constexpr (kBigEndian) {
    if constexpr (sizeof(Bits) == 4) bits = __builtin_bswap32(bits);
    else bits = __builtin_bswap64(bits);
  }
  return std::bit_cast<Real>(bits);
}

// Walks the data triplets, filling t. Returns the number of bytes consumed.
template <typename Real, bool kBigEndian>
void read_points(const std::string& path, std::span<const std::uint8_t> bytes, std::uint64_t offset, Tractogram& t) {
  constexpr std::size_t kTriplet = 3 * sizeof(Real);
  const std::uint64_t available = (bytes.size() - offset) / kTriplet;
  t.positions.reserve(3 * available);
  const std::uint8_t* p = bytes.data() + offset;
  bool terminated = false;
  std::uint64_t points_in_current = 0;
  for (std::uint64_t i = 0; i < available; ++i, p += kTriplet) {
    Real x = load<Real, kBigEndian>(p), y = load<Real, kBigEndian>(p + sizeof(Real)),
         z = load<Real, kBigEndian>(p + 2 * sizeof(Real));
    if (std::isnan(x)) {  // end of streamline
      t.offsets.push_back(t.point_count());
      points_in_current = 0;
      continue;
    }
    if (std::isinf(x)) {  // end of file
      terminated = true;
      break;
    }
    if (!std::isfinite(y) || !std::isfinite(z))
      fail_input(path, offset + i * kTriplet, "non-finite coordinate inside a streamline (only x marks NaN/Inf delimiters)");
    t.positions.push_back(static_cast<float>(x));
    t.positions.push_back(static_cast<float>(y));
    t.positions.push_back(static_cast<float>(z));
    ++points_in_current;
  }
  if (!terminated) {
    std::uint64_t trailing = (bytes.size() - offset) % kTriplet;
    std::string w = "no Inf terminator before end of file (tolerated, as MRtrix does)";
    if (trailing != 0) w += "; " + std::to_string(trailing) + " trailing bytes ignored";
    t.source.warnings.push_back(w);
    if (points_in_current > 0) {
      t.offsets.push_back(t.point_count());
      t.source.warnings.push_back("last streamline (" + std::to_string(points_in_current) +
                                  " points) has no NaN delimiter: kept");
    }
  } else if (points_in_current > 0) {
    // MRtrix writes a NaN before the Inf; without it the points still form a streamline.
    t.offsets.push_back(t.point_count());
  }
}

}  // namespace

Tractogram read_tck(const std::string& path) {
  MappedFile file(path);
  TckHeader h = parse_header(path, file.bytes());
  Tractogram t;
  t.source.path = path;
  t.source.format = "tck";
  t.source.dtype = h.datatype;
  t.source.bytes = file.size();
  t.source.xxh3_128 = xxh3_128_hex(file.data(), file.size());
  t.source.header = h.fields;

  const std::string& dt = h.datatype;
  if (dt == "Float32LE") read_points<float, false>(path, file.bytes(), h.data_offset, t);
  else if (dt == "Float32BE") read_points<float, true>(path, file.bytes(), h.data_offset, t);
  else if (dt == "Float64LE") read_points<double, false>(path, file.bytes(), h.data_offset, t);
  else if (dt == "Float64BE") read_points<double, true>(path, file.bytes(), h.data_offset, t);
  else fail_unsupported(path, "TCK datatype '" + dt + "' (expected Float32LE, Float32BE, Float64LE or Float64BE)");

  if (dt.starts_with("Float64"))
    t.source.warnings.push_back("Float64 coordinates rounded to float32 (spec §8)");
  if (h.count && *h.count != t.streamline_count())
    t.source.warnings.push_back("header count " + std::to_string(*h.count) + " disagrees with the data (" +
                                std::to_string(t.streamline_count()) + " streamlines): the data is trusted");
  return t;
}

}  // namespace vxl
