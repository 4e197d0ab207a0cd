#include "converter/cli/info_summary.h"

#include <cstdio>
#include <string>

namespace vxl::cli {
namespace {

std::string string_field(const nlohmann::json& object, const char* key) {
  if (!object.is_object()) return "";
  auto it = object.find(key);
  return it != object.end() && it->is_string() ? it->get<std::string>() : "";
}
std::uint64_t count_field(const nlohmann::json& object, const char* key) {
  if (!object.is_object()) return 0;
  auto it = object.find(key);
  return it != object.end() && it->is_number_unsigned() ? it->get<std::uint64_t>() : 0;
}

}  // namespace

void add_meta_summary(const FileHeader& header, const MetaSection& m, nlohmann::json& info) {
  info["version"] = std::to_string(header.version_major) + "." + std::to_string(header.version_minor);
  info["streamlines"] = m.streamline_count;
  info["points"] = m.point_count;
  info["voxels"] = m.voxel_count;
  info["voxlines"] = m.voxline_count;
  info["voxel_size"] = m.voxel_size;
  info["grid_dims"] = {m.grid_dims[0], m.grid_dims[1], m.grid_dims[2]};
  info["bounds"] = {{"min", {m.bounds_min[0], m.bounds_min[1], m.bounds_min[2]}},
                    {"max", {m.bounds_max[0], m.bounds_max[1], m.bounds_max[2]}}};
  info["stored_orders"] = m.stored_order_count;
}

void add_provenance_summary(const nlohmann::json& provenance, nlohmann::json& info) {
  if (!provenance.is_object()) return;
  if (provenance.contains("source") && provenance["source"].is_object()) {
    const nlohmann::json& src = provenance["source"];
    info["source"] = {{"name", string_field(src, "name")},
                      {"format", string_field(src, "format")},
                      {"bytes", count_field(src, "bytes")}};
  }
  // How the voxel size was chosen, when --voxel-size auto chose it.
  if (provenance.contains("converter") && provenance["converter"].is_object())
    if (const std::string why = string_field(provenance["converter"], "voxel_size_auto"); !why.empty())
      info["voxel_size_choice"] = why;
}

void print_source_line(const nlohmann::json& info) {
  if (!info.contains("source")) return;
  std::printf("source        %s (%s, %llu bytes)\n", info["source"]["name"].get<std::string>().c_str(),
              info["source"]["format"].get<std::string>().c_str(),
              (unsigned long long)info["source"]["bytes"].get<std::uint64_t>());
}

}  // namespace vxl::cli
