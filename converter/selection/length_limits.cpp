#include "converter/selection/length_limits.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "format/base/error.h"
#include "format/base/json_limits.h"

namespace vxl {
namespace {

std::string_view strip(std::string_view s) {
  constexpr std::string_view ws{" \0\t\r\n", 5};
  const std::size_t first = s.find_first_not_of(ws);
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(ws) + 1 - first);
}

// A key of the source header (PROV "source"."header": one string per line that named it) as MRtrix's reader
// gives it: each line's value up to a '#' (a comment) and stripped, the lines joined by '\n'. The TCK reader
// appends a following line without a colon to the value before it; MRtrix skips such a line, so only the
// first line of each value counts. std::nullopt when the header lacks the key.
std::optional<std::string> mrtrix_header_value(const nlohmann::json& header, const char* key) {
  if (!header.is_object() || !header.contains(key)) return std::nullopt;
  const nlohmann::json& lines = header[key];
  std::string joined;
  auto add = [&](const nlohmann::json& line) {
    if (!line.is_string()) return;
    std::string_view v = line.get_ref<const std::string&>();
    v = strip(v.substr(0, std::min(v.find('\n'), v.find('#'))));
    joined = joined.empty() ? std::string(v) : joined + "\n" + std::string(v);
  };
  if (lines.is_array())
    for (const nlohmann::json& line : lines) add(line);
  else
    add(lines);
  return joined;
}

// The source header kept in PROV (null when there is none), read once for all its keys.
nlohmann::json source_header(const VxlFile& file) {
  const nlohmann::json prov = parse_json(file.provenance_json(), file.path(), file.provenance_offset(), "PROV");
  if (!prov.is_object() || !prov.contains("source") || !prov["source"].is_object()) return nullptr;
  return prov["source"].value("header", nlohmann::json());
}

}  // namespace

std::optional<float> mrtrix_float(std::string_view text) {
  const std::string stripped(strip(text));
  std::istringstream stream(stripped);
  float value;
  stream >> value;
  if (stream.fail()) {
    std::string lower = stripped;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    if (lower == "nan") return std::numeric_limits<float>::quiet_NaN();
    if (lower == "-nan") return -std::numeric_limits<float>::quiet_NaN();
    if (lower == "inf") return std::numeric_limits<float>::infinity();
    if (lower == "-inf") return -std::numeric_limits<float>::infinity();
    return std::nullopt;
  }
  if (!stream.eof()) return std::nullopt;
  return value;
}

LengthLimits tckedit_length_limits(const VxlFile& file, std::optional<double> min_length,
                                   std::optional<double> max_length) {
  LengthLimits limits;
  // tckedit rounds each option (a double) to float32 for its header, then reads it back: the same float.
  if (min_length) limits.min = static_cast<float>(*min_length);
  if (max_length) limits.max = static_cast<float>(*max_length);
  const nlohmann::json header = source_header(file);
  const std::optional<std::string> step_text = mrtrix_header_value(header, "step_size");
  const std::optional<float> step = step_text ? mrtrix_float(*step_text) : std::nullopt;
  if (!step || !std::isfinite(*step)) return limits;
  float error_margin = 0.1f;
  if (const std::optional<std::string> downsample_text = mrtrix_header_value(header, "downsample_factor")) {
    const std::optional<float> downsample = mrtrix_float(*downsample_text);
    if (!downsample)
      fail_input(file.path(), file.provenance_offset(),
                 "the source header's downsample_factor '" + *downsample_text +
                     "' is not a number: tckedit refuses to edit such a file");
    error_margin = static_cast<float>(0.5 / *downsample);
  }
  limits.max += error_margin * *step;
  limits.min -= error_margin * *step;
  return limits;
}

}  // namespace vxl
