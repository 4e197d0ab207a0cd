// TCK reader (MRtrix3 tracks file).
//
// Coordinate convention: TCK stores world coordinates, RAS mm, as-is; we convert to float32 (exact for
// Float32 files, rounded to nearest for Float64 files: spec §8).
//
// Layout: text header "mrtrix tracks" / "key: value" lines (keys may repeat) / "END"; the data starts at
// the byte offset in "file: . OFFSET". Data: xyz triplets; a triplet whose x is NaN ends a streamline, one
// whose x is Inf ends the file. Like MRtrix we tolerate a missing Inf terminator at EOF, and trust the data
// over a stale "count".
#include <string_view>

#include "checksum.h"
#include "error.h"
#include "mapped_file.h"
#include "read_tractogram.h"
#include "tck_format.h"

namespace vxl {
namespace tck {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  return s;
}

}  // namespace

std::optional<Header> parse_header(const std::string& path, std::span<const std::uint8_t> bytes, std::uint64_t file_size) {
  Header h;
  std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  std::size_t pos = 0;
  // With only the first bytes of a longer file, a line that runs to their end may be cut: it is not
  // judged (nor the magic line) until more is read, so a streamed header fails exactly where a whole one does.
  const bool partial = bytes.size() < file_size;
  bool cut = false;
  auto next_line = [&](std::string_view& line) {
    if (pos >= text.size()) return false;
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) {
      if (partial) {
        cut = true;
        return false;
      }
      end = text.size();
    }
    line = text.substr(pos, end - pos);
    pos = end + 1;
    return true;
  };
  std::string_view line;
  if (!next_line(line)) {
    if (cut) return std::nullopt;
    fail_input(path, 0, "expected the TCK magic line 'mrtrix tracks'");
  }
  if (trim(line) != "mrtrix tracks") fail_input(path, 0, "expected the TCK magic line 'mrtrix tracks'");
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
  if (!ended) {
    if (bytes.size() < file_size) return std::nullopt;
    fail_input(path, bytes.size(), "TCK header has no 'END' line");
  }

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
  if (h.data_offset > file_size)
    fail_input(path, h.data_offset, "TCK data offset is past the end of the file (" + std::to_string(file_size) + " bytes)");
  if (h.fields.contains("count")) {
    try {
      h.count = std::stoull(h.fields["count"].back().get<std::string>());
    } catch (const std::exception&) {
      // a malformed count is as good as a stale one: we trust the data
    }
  }
  return h;
}

void finish(const DecodeState& s, std::uint64_t trailing, Tractogram& t, std::vector<std::string>& warnings) {
  if (!s.terminated) {
    std::string w = "no Inf terminator before end of file (tolerated, as MRtrix does)";
    if (trailing != 0) w += "; " + std::to_string(trailing) + " trailing bytes ignored";
    warnings.push_back(w);
    if (s.points_in_current > 0) {
      t.offsets.push_back(t.point_count());
      warnings.push_back("last streamline (" + std::to_string(s.points_in_current) + " points) has no NaN delimiter: kept");
    }
  } else if (s.points_in_current > 0) {
    // MRtrix writes a NaN before the Inf; without it the points still form a streamline.
    t.offsets.push_back(t.point_count());
  }
}

void header_warnings(const Header& h, std::uint64_t streamlines, std::vector<std::string>& warnings) {
  if (h.datatype.starts_with("Float64")) warnings.push_back("Float64 coordinates rounded to float32 (spec §8)");
  if (h.count && *h.count != streamlines)
    warnings.push_back("header count " + std::to_string(*h.count) + " disagrees with the data (" +
                       std::to_string(streamlines) + " streamlines): the data is trusted");
}

}  // namespace tck

namespace {

// Walks all data triplets into t.
template <typename Real, bool kBigEndian>
void read_points(const std::string& path, std::span<const std::uint8_t> bytes, std::uint64_t offset, Tractogram& t) {
  constexpr std::size_t kTriplet = 3 * sizeof(Real);
  const std::uint64_t available = (bytes.size() - offset) / kTriplet;
  t.positions.reserve(3 * available);
  tck::DecodeState s;
  tck::decode<Real, kBigEndian>(path, bytes.data() + offset, available, offset, t, s, ~std::uint64_t(0));
  tck::finish(s, (bytes.size() - offset) % kTriplet, t, t.source.warnings);
}

}  // namespace

Tractogram read_tck(const std::string& path) {
  MappedFile file(path);
  tck::Header h = *tck::parse_header(path, file.bytes(), file.size());
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

  tck::header_warnings(h, t.streamline_count(), t.source.warnings);
  return t;
}

}  // namespace vxl
