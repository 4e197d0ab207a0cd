#include "converter/readers/read_tsf.h"

#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "converter/readers/mrtrix_header.h"
#include "converter/readers/regular_file.h"
#include "format/base/checksum.h"
#include "format/base/error.h"
#include "format/base/mapped_file.h"

namespace vxl {
namespace {

std::string shortest(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

template <typename Real, bool kBigEndian>
void read_values(const std::string& path, std::span<const std::uint8_t> bytes, std::uint64_t offset, TrackScalars& s) {
  const std::uint64_t available = (bytes.size() - offset) / sizeof(Real);
  s.values.reserve(available);
  const std::uint8_t* p = bytes.data() + offset;
  bool terminated = false;
  std::uint64_t in_current = 0;
  for (std::uint64_t i = 0; i < available; ++i, p += sizeof(Real)) {
    const Real v = load_mrtrix_value<Real, kBigEndian>(p);
    if (std::isnan(v)) {  // end of streamline
      s.offsets.push_back(s.values.size());
      in_current = 0;
      continue;
    }
    if (std::isinf(v)) {  // end of file
      terminated = true;
      break;
    }
    // Values are kept as float32; a Float64 value beyond its range would become an Inf that no range,
    // colour map or export can use. Refused, as conversion refuses such a Float64 TCK coordinate.
    if (!std::isfinite(static_cast<float>(v)))
      fail_input(
          path, offset + i * sizeof(Real),
          "a value (" + shortest(v) + ")" + " is beyond the float32 range (Float64 values are stored as float32)");
    s.values.push_back(static_cast<float>(v));
    ++in_current;
  }
  // Real TSF files (MRtrix's test data, NiiVue's demos) end with a streamline's NaN and no Inf: that is no
  // reason to warn. A last streamline without its NaN, or a partial value, is.
  const std::uint64_t trailing = (bytes.size() - offset) % sizeof(Real);
  if (!terminated && in_current > 0)
    s.warnings.push_back("file ends inside a streamline (no NaN, no Inf): its " + std::to_string(in_current) +
                         " values are kept, as MRtrix does");
  if (!terminated && trailing != 0) s.warnings.push_back(std::to_string(trailing) + " trailing bytes ignored");
  if (in_current > 0) s.offsets.push_back(s.values.size());  // a last streamline without its NaN
}

}  // namespace

TrackScalars read_tsf(const std::string& path) {
  require_regular_file(path);
  MappedFile file(path);
  const MrtrixHeader h = parse_mrtrix_header(path, file.bytes(), kTsfFile);
  TrackScalars s;
  s.offsets = {0};
  s.timestamp = h.last("timestamp");
  s.provenance = {{"name", std::filesystem::path(path).filename().string()},
                  {"bytes", file.size()},
                  {"xxh3_128", xxh3_128_hex(file.data(), file.size())},
                  {"header", h.fields}};
  const MrtrixDatatype type = mrtrix_datatype(path, h.datatype, kTsfFile);
  visit_mrtrix_datatype(type, [&]<typename Real, bool kBigEndian>() {
    read_values<Real, kBigEndian>(path, file.bytes(), h.data_offset, s);
  });
  if (auto w = count_warning(h, s.offsets.size() - 1)) s.warnings.push_back(*w);
  return s;
}

void attach_tsf(Tractogram& t, const std::string& tsf_path) {
  TrackScalars s = read_tsf(tsf_path);
  const std::uint64_t n = s.offsets.size() - 1;
  const std::string counts = std::to_string(n) + " streamlines and " + std::to_string(s.values.size()) + " values";
  const std::string expected =
      std::to_string(t.streamline_count()) + " streamlines and " + std::to_string(t.point_count()) + " points";
  const std::string source = t.source.path.empty() ? "the tractogram" : t.source.path;
  if (n != t.streamline_count() || s.values.size() != t.point_count())
    fail_input(tsf_path, std::nullopt,
               "holds " + counts + " but " + source + " has " + expected + ": a TSF must have one value per point");
  for (std::uint64_t i = 0; i < n; ++i)
    if (s.offsets[i + 1] - s.offsets[i] != t.offsets[i + 1] - t.offsets[i])
      fail_input(tsf_path, std::nullopt,
                 "streamline " + std::to_string(i) + " has " + std::to_string(s.offsets[i + 1] - s.offsets[i]) +
                     " values but " + std::to_string(t.offsets[i + 1] - t.offsets[i]) + " points in " + source);
  const std::string name = std::filesystem::path(tsf_path).stem().string();
  for (const std::string& w : s.warnings) t.source.warnings.push_back(name + ".tsf: " + w);
  if (s.timestamp && t.source.header.is_object() && t.source.header.contains("timestamp")) {
    const auto& ts = t.source.header["timestamp"];
    if (ts.is_array() && !ts.empty() && ts.back().is_string() && ts.back().get<std::string>() != *s.timestamp)
      t.source.warnings.push_back(name +
                                  ".tsf: its timestamp differs from the tractogram's (the counts agree, so it "
                                  "is used)");
  }
  t.point_values.push_back({name, std::move(s.values)});
  t.source.value_files.push_back(std::move(s.provenance));
}

}  // namespace vxl
