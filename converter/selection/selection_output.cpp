#include "converter/selection/selection_output.h"

#include <algorithm>

#include <nlohmann/json.hpp>

#include "converter/convert/convert.h"
#include "converter/export/export_trk.h"
#include "converter/export/export_trx.h"
#include "converter/export/export_values.h"
#include "converter/export/export_vtk.h"
#include "converter/export/groups_not_written.h"
#include "converter/export/streamline_outputs.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/vxl_streamlines.h"

namespace vxl {
namespace {

// The source block of the .vxl's provenance (spec §5.8), as the readers filled it; fields of the wrong
// type are left empty (PROV may hold any JSON).
SourceInfo source_of(const VxlFile& file) {
  SourceInfo info;
  info.path = file.path();
  const nlohmann::json prov = parse_json(file.provenance_json(), file.path(), file.provenance_offset(), "PROV");
  if (!prov.is_object() || !prov.contains("source") || !prov["source"].is_object()) return info;
  const nlohmann::json& src = prov["source"];
  auto text = [&](const char* key) {
    return src.contains(key) && src[key].is_string() ? src[key].get<std::string>() : std::string();
  };
  if (!text("name").empty()) info.path = text("name");
  info.format = text("format");
  info.dtype = text("dtype");
  info.xxh3_128 = text("xxh3_128");
  if (src.contains("bytes") && src["bytes"].is_number_unsigned()) info.bytes = src["bytes"].get<std::uint64_t>();
  if (src.contains("header")) info.header = src["header"];
  if (src.contains("vox_to_ras") && src["vox_to_ras"].is_array() && src["vox_to_ras"].size() == 16 &&
      std::all_of(src["vox_to_ras"].begin(), src["vox_to_ras"].end(), [](const auto& x) { return x.is_number(); }))
    info.vox_to_ras = src["vox_to_ras"].get<std::array<double, 16>>();
  return info;
}

// The conversion settings the .vxl was made with, from META (and PROV for the orders' name).
ConvertSettings settings_of(const VxlFile& file) {
  ConvertSettings s;
  const MetaSection& m = file.meta();
  s.voxel_size = m.voxel_size;
  s.positions = file.position_encoding();
  s.levels = file.level_count();
  s.orders = m.order_set == 0   ? "axis"
             : m.order_set == 1 ? "axis+diag"
                                : "random:" + std::to_string(m.stored_order_count);
  return s;
}

// The subset as an in-memory tractogram: positions, values, groups and their rows (GDAT).
Tractogram subset_tractogram(const VxlFile& file, const StreamlineSubset& subset) {
  Tractogram t;
  t.source = source_of(file);
  WalkCallbacks cb;
  cb.threads = 0;  // the points decoded on every core
  cb.read_points = [&](std::uint64_t s) { return subset.contains(s); };
  cb.streamline = [&](std::uint64_t, std::span<const float> xyz) { t.add_streamline(xyz.data(), xyz.size() / 3); };
  walk_streamlines(file, cb);
  const ValueSets& per_point = file.vertex_values();
  if (!per_point.empty()) {
    const std::vector<std::uint64_t> vertices = source_vertex_indices(file, &subset);
    for (std::uint32_t k = 0; k < per_point.size(); ++k)
      t.point_values.push_back({per_point.name(k), values_at(file, k, vertices)});
  }
  const ValueSets& per_streamline = file.streamline_values();
  for (std::uint32_t k = 0; k < per_streamline.size(); ++k)
    t.streamline_values.push_back({per_streamline.name(k), subset.pick(per_streamline.values(k))});
  for (StreamlineGroup& g : file.groups()) {
    g.members = subset.renumber(g.members);
    t.groups.push_back(std::move(g));
  }
  t.group_values = file.group_values();  // a group's row describes the group, kept with it
  return t;
}

}  // namespace

bool is_selection_output(const std::string& path) { return streamline_output_of(path, false).has_value(); }

std::vector<std::string> write_selection(const VxlFile& file, const StreamlineSubset& subset,
                                         const std::string& out_path, const TckExportSettings& tck,
                                         const std::vector<std::string>& header) {
  const std::optional<StreamlineOutput> format = streamline_output_of(out_path, false);
  if (!format)
    throw Error(ErrorKind::Usage, out_path, std::nullopt,
                "a selection is written to " + streamline_output_suffixes(false));
  if (*format == StreamlineOutput::Tck) return export_tck(file, out_path, tck, &subset, header).warnings;
  if (tck.tsf_path || tck.value)
    throw Error(ErrorKind::Usage, out_path, std::nullopt,
                "--tsf and --value go with a .tck output (a .trx, .vtk, .trk or .vxl holds the value sets)");
  switch (*format) {
    case StreamlineOutput::Tck: break;
    case StreamlineOutput::Trx: export_trx(file, out_path, &subset); break;
    case StreamlineOutput::Trk: return export_trk(file, out_path, &subset).warnings;
    case StreamlineOutput::Vtk:
      export_vtk(file, out_path, &subset);
      if (std::optional<std::string> lost = group_values_not_written(file, "a VTK")) return {*lost};
      break;
    case StreamlineOutput::Vxl: convert_tractogram(subset_tractogram(file, subset), out_path, settings_of(file)); break;
  }
  return {};
}

}  // namespace vxl
