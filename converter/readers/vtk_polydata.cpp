#include "converter/readers/vtk_polydata.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <set>

#include "format/base/checked_count.h"
#include "format/base/checksum.h"
#include "format/base/error.h"

namespace vxl::vtk {
namespace {

// The value sets one array gives (see the header), or none with a warning.
void add_value_sets(Tractogram& t, const DataArray& a, std::uint64_t tuples, std::uint64_t first_tuple,
                    const std::vector<std::uint64_t>* gather, const std::vector<std::uint64_t>& line_offsets,
                    bool per_point, const std::string& path, std::set<std::string>& used) {
  const char* where = per_point ? "point data" : "cell data";
  if (a.values.size() != checked_product(tuples, a.components, path, std::nullopt, std::string(where) + " size"))
    fail_input(path, std::nullopt,
               std::string(where) + " array '" + a.name + "' has " + std::to_string(a.values.size()) +
                   " values; expected " + std::to_string(tuples) + " x " + std::to_string(a.components));
  if (a.components > kMaxComponentsKept) {
    t.source.warnings.push_back(std::string(where) + " array '" + a.name + "' has " + std::to_string(a.components) +
                                " components; only arrays of 1 to 4 are kept as value sets");
    return;
  }
  for (std::uint64_t c = 0; c < a.components; ++c) {
    std::string name = a.components == 1 ? a.name : a.name + "[" + std::to_string(c) + "]";
    if (name.empty()) name = per_point ? "point_data" : "cell_data";
    if (!used.insert(name).second) {
      t.source.warnings.push_back(std::string(where) + " array '" + name + "' appears twice; the second is skipped");
      continue;
    }
    ValueSet v;
    v.name = name;
    if (per_point) {
      v.values.reserve(gather->size());
      for (std::uint64_t i : *gather) v.values.push_back(static_cast<float>(a.values[i * a.components + c]));
      t.point_values.push_back(std::move(v));
    } else {
      const std::uint64_t lines = line_offsets.size() - 1;
      v.values.reserve(lines);
      for (std::uint64_t k = 0; k < lines; ++k)
        v.values.push_back(static_cast<float>(a.values[(first_tuple + k) * a.components + c]));
      t.streamline_values.push_back(std::move(v));
    }
  }
}

}  // namespace

void fill_tractogram(Tractogram& t, const std::string& path, const PolyData& p, bool lps) {
  if (p.points.size() != checked_product(3, p.point_count, path, std::nullopt, "POINTS count"))
    fail_input(path, std::nullopt,
               "POINTS holds " + std::to_string(p.points.size()) + " coordinates; expected 3 x " +
                   std::to_string(p.point_count));
  const std::uint64_t lines = p.line_offsets.size() - 1;
  if (p.line_offsets.back() != p.line_connectivity.size())
    fail_input(path, std::nullopt,
               "line offsets end at " + std::to_string(p.line_offsets.back()) + " but the connectivity has " +
                   std::to_string(p.line_connectivity.size()) + " entries");
  // The points of every streamline, gathered: a line may use any point, in any order, more than once.
  std::vector<std::uint64_t> gather;
  gather.reserve(p.line_connectivity.size());
  for (std::uint64_t k = 0; k < lines; ++k) {
    if (p.line_offsets[k + 1] < p.line_offsets[k])
      fail_input(path, std::nullopt, "line offsets decrease at line " + std::to_string(k));
    for (std::uint64_t j = p.line_offsets[k]; j < p.line_offsets[k + 1]; ++j) {
      const double i = p.line_connectivity[j];
      if (!(i >= 0 && i < static_cast<double>(p.point_count)) || i != std::floor(i))
        fail_input(path, std::nullopt,
                   "line " + std::to_string(k) + " refers to point " + std::to_string(i) + " of " +
                       std::to_string(p.point_count) + " (expected 0 to point count - 1)");
      gather.push_back(static_cast<std::uint64_t>(i));
    }
  }
  const float sign = lps ? -1.0f : 1.0f;
  t.positions.reserve(3 * gather.size());
  for (std::uint64_t i : gather) {
    // Rounded once to float32: float32 sources are kept bit-exactly.
    t.positions.push_back(sign * static_cast<float>(p.points[3 * i]));
    t.positions.push_back(sign * static_cast<float>(p.points[3 * i + 1]));
    t.positions.push_back(static_cast<float>(p.points[3 * i + 2]));
  }
  t.offsets.assign(p.line_offsets.begin(), p.line_offsets.end());
  std::set<std::string> point_names, cell_names;
  for (const DataArray& a : p.point_data)
    add_value_sets(t, a, p.point_count, 0, &gather, p.line_offsets, true, path, point_names);
  if (!p.cell_data.empty() &&
      checked_sum(p.cells_before_lines, lines, path, std::nullopt, "cells up to the last line") > p.cell_count)
    fail_input(path, std::nullopt,
               "cell data for " + std::to_string(p.cell_count) + " cells, fewer than the cells declared");
  for (const DataArray& a : p.cell_data)
    add_value_sets(t, a, p.cell_count, p.cells_before_lines, nullptr, p.line_offsets, false, path, cell_names);
}

std::string decode_name(const std::string& name) {
  std::string out;
  for (std::size_t k = 0; k < name.size(); ++k) {
    if (name[k] == '%' && k + 2 < name.size() && std::isxdigit(static_cast<unsigned char>(name[k + 1])) &&
        std::isxdigit(static_cast<unsigned char>(name[k + 2]))) {
      out += static_cast<char>(std::stoi(name.substr(k + 1, 2), nullptr, 16));
      k += 2;
    } else {
      out += name[k];
    }
  }
  return out;
}

bool says_lps(const std::string& text) {
  std::string upper = text;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  upper.erase(std::remove_if(upper.begin(), upper.end(), [](char c) { return c == ' ' || c == '\t'; }), upper.end());
  return upper.find("SPACE=LPS") != std::string::npos;
}

std::uint64_t load_uint(const std::uint8_t* p, unsigned size, bool big_endian) {
  std::uint64_t v = 0;
  for (unsigned k = 0; k < size; ++k) v |= std::uint64_t(p[big_endian ? k : size - 1 - k]) << (8 * (size - 1 - k));
  return v;
}

double load_number(const std::uint8_t* p, char kind, unsigned size, bool big_endian) {
  const std::uint64_t u = load_uint(p, size, big_endian);
  if (kind == 'f') {
    if (size == 4) return std::bit_cast<float>(static_cast<std::uint32_t>(u));
    return std::bit_cast<double>(u);
  }
  if (kind == 'u') return static_cast<double>(u);
  const unsigned shift = 64 - 8 * size;  // sign-extend
  return static_cast<double>(static_cast<std::int64_t>(u << shift) >> shift);
}

void describe_source(Tractogram& t, const std::string& path, const char* format, std::span<const std::uint8_t> bytes) {
  t.source.path = path;
  t.source.format = format;
  t.source.bytes = bytes.size();
  t.source.xxh3_128 = xxh3_128_hex(bytes.data(), bytes.size());
}

}  // namespace vxl::vtk
