#include "converter/cli/package_info.h"

#include <cstdio>
#include <string>
#include <vector>

#include "converter/cli/info_summary.h"
#include "converter/package/unpack.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/vxlz_layout.h"

namespace vxl::cli {

nlohmann::json package_info(const VxlzFile& package) {
  const MetaSection& m = package.meta();
  const PackSection& p = package.pack();
  nlohmann::json j;
  j["file"] = package.path();
  j["format"] = "vxlz";
  add_meta_summary(package.header(), m, j);
  j["bytes"] = package.size();
  try {
    j["unpacked_bytes"] = unpacked_vxl_bytes(package, UnpackSettings());  // unpack's defaults, as the web page's
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::Unsupported) throw;  // a damaged package is refused, as unpack refuses it
    j["unpacked_bytes"] = nullptr;
    j["unpack_unsupported"] = e.what();
  }
  j["positions"] = {{"quantization_bits", p.quantization_bits},
                    {"quantum_mm", p.quantum},
                    {"error_bound_mm", p.error_bound},
                    {"max_error_mm", p.max_error},
                    {"rms_error_mm", p.rms_error}};
  j["chunks"] = {{"count", p.chunk_count}, {"points", p.chunk_points}, {"checksums", package.has_chunk_checksums()}};
  const bool level_order = p.predictor == kVxlzPredictorLinearLevelOrder;
  j["shipping_order"] = level_order ? "level" : "streamline";
  if (level_order) {
    nlohmann::json levels = nlohmann::json::array();
    for (const ShippedLevel& l : shipped_levels(package))
      levels.push_back({{"level", l.level}, {"streamlines", l.streamlines}, {"points", l.points}, {"bytes", l.bytes}});
    j["levels"] = levels;
  }
  nlohmann::json sections = nlohmann::json::array();
  for (const SectionEntry& e : package.sections())
    sections.push_back({{"id", std::string(e.id, 4)}, {"offset", e.offset}, {"bytes", e.size}});
  j["sections"] = sections;
  if (package.has_section(section_id("PROV"))) {
    const std::vector<std::uint8_t> raw = package.inflate(section_id("PROV"));
    add_provenance_summary(
        parse_json({reinterpret_cast<const char*>(raw.data()), raw.size()}, package.path(), std::nullopt, "PROV"), j);
  }
  return j;
}

void print_package_info(const nlohmann::json& j) {
  const std::string unpacked =
      j["unpacked_bytes"].is_null()
          ? "voxlines unpack cannot make its .vxl: " + j["unpack_unsupported"].get<std::string>()
          : "voxlines unpack makes a .vxl of " + std::to_string(j["unpacked_bytes"].get<std::uint64_t>()) + " bytes";
  std::printf("file          %s (.vxlz %s, %llu bytes: a package; %s)\n", j["file"].get<std::string>().c_str(),
              j["version"].get<std::string>().c_str(), (unsigned long long)j["bytes"].get<std::uint64_t>(),
              unpacked.c_str());
  print_source_line(j);
  const auto& grid = j["grid_dims"];
  std::printf("streamlines   %llu\npoints        %llu\nvoxels        %u (grid %d x %d x %d), %g mm\n",
              (unsigned long long)j["streamlines"].get<std::uint64_t>(),
              (unsigned long long)j["points"].get<std::uint64_t>(), j["voxels"].get<std::uint32_t>(),
              grid[0].get<int>(), grid[1].get<int>(), grid[2].get<int>(), j["voxel_size"].get<double>());
  const auto& pos = j["positions"];
  std::printf("positions     %u bits per axis (quantum %.3g um; error at most %.3g um, largest %.3g um, rms %.3g um)\n",
              pos["quantization_bits"].get<std::uint32_t>(), 1000 * pos["quantum_mm"].get<double>(),
              1000 * pos["error_bound_mm"].get<double>(), 1000 * pos["max_error_mm"].get<double>(),
              1000 * pos["rms_error_mm"].get<double>());
  std::printf("chunks        %llu of %llu points%s\n", (unsigned long long)j["chunks"]["count"].get<std::uint64_t>(),
              (unsigned long long)j["chunks"]["points"].get<std::uint64_t>(),
              j["chunks"]["checksums"].get<bool>() ? ", each with its own checksum (a prefix's are checked)" : "");
  if (j["shipping_order"] == "level") {
    std::printf("shipped       level by level, the coarsest first: each level whole in the package's first bytes\n");
    for (const auto& l : j["levels"])
      std::printf("  level %u     %llu streamlines, %llu points, in the first %llu bytes\n",
                  l["level"].get<std::uint32_t>(), (unsigned long long)l["streamlines"].get<std::uint64_t>(),
                  (unsigned long long)l["points"].get<std::uint64_t>(),
                  (unsigned long long)l["bytes"].get<std::uint64_t>());
  } else {
    std::printf("shipped       in streamline order (the whole package before any picture)\n");
  }
  std::printf("sections     ");
  for (const auto& e : j["sections"])
    std::printf(" %s:%llu", e["id"].get<std::string>().c_str(), (unsigned long long)e["bytes"].get<std::uint64_t>());
  std::printf("\n");
}

}  // namespace vxl::cli
