#include "converter/export/export_tck.h"

#include <cmath>
#include <filesystem>
#include <set>

#include <nlohmann/json.hpp>

#include "converter/export/export_values.h"
#include "converter/export/groups_not_written.h"
#include "converter/export/tck_writer.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/base/output_path.h"
#include "format/vxl_streamlines.h"

namespace vxl {
namespace {

// The source TCK header's properties (step_size, method, max_dist, ROIs, command_history, …) as tckedit
// carries them over, so that MRtrix tools reading the export (tcksift, length thresholds) still see them:
// one "key: value" line per value (multi-line values one line each), the keys the writer owns (datatype,
// file, count, total_count) and those `own_keys` sets left out, "roi" renamed "prior_roi". The timestamp
// is the source's, unlike tckedit's new one: the streamlines are the source's, so its TSF files stay
// valid with the export. Nothing for a source of another format.
std::vector<std::string> source_header_lines(const VxlFile& file, const std::set<std::string>& own_keys) {
  const nlohmann::json prov = parse_json(file.provenance_json(), file.path(), file.provenance_offset(), "PROV");
  if (!prov.is_object() || !prov.contains("source") || !prov["source"].is_object()) return {};
  const nlohmann::json& source = prov["source"];
  if (source.value("format", nlohmann::json()) != "tck") return {};
  const nlohmann::json header = source.value("header", nlohmann::json());
  if (!header.is_object()) return {};
  static const std::set<std::string> kWriters = {"datatype", "file", "count", "total_count", "voxlines_exported_from"};
  std::vector<std::string> lines;
  for (const auto& [key, values] : header.items()) {
    if (key.empty() || key.find_first_of(":\n\r") != std::string::npos || key == "END" || kWriters.contains(key))
      continue;
    const std::string name = key == "roi" ? "prior_roi" : key;
    if (own_keys.contains(name)) continue;
    std::vector<nlohmann::json> list = values.is_array() ? std::vector<nlohmann::json>(values.begin(), values.end())
                                                         : std::vector<nlohmann::json>{values};
    if (key == "timestamp" && !list.empty()) list.erase(list.begin(), list.end() - 1);
    for (const nlohmann::json& v : list) {
      if (!v.is_string()) continue;
      const std::string text = v.get<std::string>();
      // MRtrix reads an ROI as "TYPE SPEC" and crashes on less (tckinfo does, on such a source too).
      if (name == "prior_roi" && text.find_first_not_of(' ', text.find(' ')) == std::string::npos) continue;
      for (std::size_t from = 0; from <= text.size();) {
        std::size_t to = text.find('\n', from);
        if (to == std::string::npos) to = text.size();
        std::string part = text.substr(from, to - from);
        if (!part.empty() && part.back() == '\r') part.pop_back();
        lines.push_back(name + ": " + part);
        from = to + 1;
      }
    }
  }
  return lines;
}

// The keys of "key: value" lines.
std::set<std::string> keys_of(const std::vector<std::string>& lines) {
  std::set<std::string> keys;
  for (const std::string& line : lines) keys.insert(line.substr(0, line.find(':')));
  return keys;
}

// The set a TSF is asked for, by name or the first.
std::uint32_t chosen_set(const VxlFile& file, const TckExportSettings& settings) {
  const ValueSets& sets = file.vertex_values();
  if (sets.empty())
    throw Error(ErrorKind::Usage, file.path(), std::nullopt, "has no per-point values (VVAL) to write to a TSF");
  if (!settings.value) return 0;
  const int k = sets.find(*settings.value);
  if (k < 0) {
    std::string names;
    for (std::uint32_t i = 0; i < sets.size(); ++i) names += (i ? ", '" : "'") + sets.name(i) + "'";
    throw Error(ErrorKind::Usage, file.path(), std::nullopt,
                "has no per-point value set '" + *settings.value + "' (it has " + names + ")");
  }
  return static_cast<std::uint32_t>(k);
}

}  // namespace

ExportSummary export_tck(const VxlFile& file, const std::string& out_path, const TckExportSettings& settings,
                         const StreamlineSubset* given_subset, const std::vector<std::string>& extra_header) {
  std::optional<StreamlineSubset> group;
  if (settings.group) {
    if (given_subset)
      throw Error(ErrorKind::Usage, out_path, std::nullopt, "a group is chosen for a selection (--group)");
    group.emplace(group_subset(file, *settings.group));
  }
  const StreamlineSubset* subset = group ? &*group : given_subset;
  // Both are renamed into place at the end: the second would replace the first.
  if (settings.tsf_path && same_output(out_path, *settings.tsf_path))
    throw Error(ErrorKind::Usage, *settings.tsf_path, std::nullopt,
                "is the same file as the TCK output " + out_path + ": the TSF needs a file of its own");
  ExportSummary summary;
  const SubsetCounts counts = subset_counts(file, subset);
  summary.streamlines = counts.streamlines;
  summary.points = counts.points;
  std::vector<std::string> header = {"voxlines_exported_from: " +
                                     std::filesystem::path(file.path()).filename().string()};
  const std::vector<std::string> source = source_header_lines(file, keys_of(extra_header));
  header.insert(header.end(), source.begin(), source.end());
  header.insert(header.end(), extra_header.begin(), extra_header.end());

  // The TSF's values, checked before anything is written.
  std::vector<float> values;
  std::uint32_t set = 0;
  if (settings.tsf_path) {
    set = chosen_set(file, settings);
    summary.value_set = file.vertex_values().name(set);
    values = values_at(file, set, source_vertex_indices(file, subset));
    for (std::size_t i = 0; i < values.size(); ++i)
      if (!std::isfinite(values[i]))
        fail_unsupported(file.path(), "value set '" + summary.value_set + "' has a non-finite value (point " +
                                          std::to_string(i) +
                                          "); a TSF cannot hold one (NaN and Inf are its separators)");
  } else if (settings.value) {
    throw Error(ErrorKind::Usage, out_path, std::nullopt,
                "a value set is chosen for a TSF, but no TSF output is given");
  }
  const ValueSets& per_point = file.vertex_values();
  if (!settings.tsf_path && !per_point.empty())
    summary.warnings.push_back(std::to_string(per_point.size()) +
                               " per-point value set(s) not written: a TCK holds positions only "
                               "(add a TSF output for one of them, or export to .trx for all)");
  if (settings.tsf_path && per_point.size() > 1)
    summary.warnings.push_back(std::to_string(per_point.size() - 1) +
                               " other per-point value set(s) not written: a TSF holds one "
                               "(export to .trx for all)");
  if (!file.streamline_values().empty())
    summary.warnings.push_back(
        std::to_string(file.streamline_values().size()) +
        " per-streamline value set(s) not written: TCK and TSF have no place for them (export to .trx)");

  if (!settings.group)
    if (std::optional<std::string> lost = groups_not_written(file, "a TCK", subset)) summary.warnings.push_back(*lost);
  if (std::optional<std::string> lost = group_values_not_written(file, "a TCK", settings.group))
    summary.warnings.push_back(*lost);

  TckWriter writer(out_path, counts.streamlines, header, counts.points);
  std::optional<TsfWriter> tsf;
  if (settings.tsf_path) tsf.emplace(*settings.tsf_path, counts.streamlines, header, counts.points);
  std::uint64_t point = 0;
  WalkCallbacks cb;
  cb.threads = 0;  // the points decoded on every core
  cb.read_points = [&](std::uint64_t s) { return in_subset(subset, s); };
  cb.streamline = [&](std::uint64_t, std::span<const float> xyz) {
    writer.add(xyz);
    if (tsf) tsf->add(std::span<const float>(values).subspan(point, xyz.size() / 3));
    point += xyz.size() / 3;
  };
  walk_streamlines(file, cb);
  writer.finish();
  if (tsf) tsf->finish();
  return summary;
}

}  // namespace vxl
