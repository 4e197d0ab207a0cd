#include "converter/convert/convert.h"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "converter/convert/memory_choice.h"
#include "converter/convert/streaming_convert.h"
#include "format/base/error.h"
#include "format/base/memory_available.h"
#include "format/vxl_value_sets.h"

namespace vxl {

std::string provenance_json(const SourceInfo& src, const ConvertSettings& settings,
                            const std::string& voxel_size_choice) {
  nlohmann::json j;
  j["source"] = {
      {"name", std::filesystem::path(src.path).filename().string()},
      {"format", src.format},
      {"bytes", src.bytes},
      {"xxh3_128", src.xxh3_128},
      {"header", src.header},
      {"dtype", src.dtype},
      {"vox_to_ras", src.vox_to_ras ? nlohmann::json(*src.vox_to_ras) : nlohmann::json(nullptr)},
  };
  j["converter"] = {{"name", "voxlines"},
                    {"version", VOXLINES_VERSION},
                    {"voxel_size", settings.voxel_size},
                    {"orders", settings.orders},
                    {"positions", position_encoding_name(settings.positions)},
                    {"levels", settings.levels}};
  if (!voxel_size_choice.empty()) j["converter"]["voxel_size_auto"] = voxel_size_choice;
  j["warnings"] = src.warnings;
  if (!src.value_files.empty()) j["value_files"] = src.value_files;
  // Invalid UTF-8 in a source header must not make the whole file unwritable: replace it.
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

namespace {

// Checks that t's value sets have a value per point or per streamline, keeps the first kMaxValueSets of
// each kind and gives them names every reader of the file accepts (`verify`, `export`, voxview). Returns
// the warnings of doing so, also added to t.source.warnings (PROV).
std::vector<std::string> prepare_value_sets(Tractogram& t) {
  for (const ValueSet& v : t.point_values)
    if (v.values.size() != t.point_count())
      throw Error(ErrorKind::Input, t.source.path, std::nullopt,
                  "value set '" + v.name + "' has " + std::to_string(v.values.size()) + " values for " +
                      std::to_string(t.point_count()) + " points");
  for (const ValueSet& v : t.streamline_values)
    if (v.values.size() != t.streamline_count())
      throw Error(ErrorKind::Input, t.source.path, std::nullopt,
                  "value set '" + v.name + "' has " + std::to_string(v.values.size()) + " values for " +
                      std::to_string(t.streamline_count()) + " streamlines");
  std::vector<std::string> warnings;
  for (auto* sets : {&t.point_values, &t.streamline_values})
    if (sets->size() > kMaxValueSets) {
      warnings.push_back("only the first " + std::to_string(kMaxValueSets) + " of " + std::to_string(sets->size()) +
                         (sets == &t.point_values ? " per-point" : " per-streamline") + " value sets are kept");
      sets->resize(kMaxValueSets);
    }
  // Names every reader of the file accepts (`verify`, `export`, voxview): mapped here, said in a warning.
  for (auto* sets : {&t.point_values, &t.streamline_values}) {
    std::vector<std::string> names;
    for (const ValueSet& v : *sets) names.push_back(v.name);
    const std::vector<std::string> usable =
        usable_value_set_names(names, sets == &t.point_values ? "point_values" : "streamline_values", warnings);
    for (std::size_t k = 0; k < sets->size(); ++k) (*sets)[k].name = usable[k];
  }
  t.source.warnings.insert(t.source.warnings.end(), warnings.begin(), warnings.end());
  return warnings;
}

}  // namespace

ConvertSummary convert_tractogram(Tractogram&& t, const std::string& out_path, const ConvertSettings& given) {
  // Warnings of the conversion itself: in PROV with the reader's, and in the summary for the caller to show.
  std::vector<std::string> warnings = prepare_value_sets(t);
  ConvertSettings settings = given;
  if (settings.memory_limit == 0) settings.memory_limit = largest_chosen_memory_limit(available_memory());
  ConvertSummary summary = convert_streaming(t, out_path, settings);
  summary.warnings = std::move(warnings);
  return summary;
}

}  // namespace vxl
