#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <nlohmann/json.hpp>

#include "converter/cli/commands.h"
#include "converter/cli/info_summary.h"
#include "converter/cli/package_info.h"
#include "converter/readers/float16.h"
#include "format/base/json_limits.h"
#include "format/vxl_file.h"

namespace vxl::cli {
namespace {

// One row of values per group (GDAT) as JSON numbers: integers exactly, floats as binary64 (NaN: null).
nlohmann::json row_numbers(const GroupValues& v) {
  nlohmann::json a = nlohmann::json::array();
  const std::size_t size = group_value_type_size(v.type);
  for (std::size_t i = 0; i < v.components; ++i) {
    const std::uint8_t* p = v.bytes.data() + i * size;
    auto load = [&](auto x) {
      std::memcpy(&x, p, sizeof x);  // little-endian, as every platform this runs on (spec §1)
      return x;
    };
    switch (v.type) {
      case GroupValueType::Uint8: a.push_back(load(std::uint8_t{})); break;
      case GroupValueType::Uint16: a.push_back(load(std::uint16_t{})); break;
      case GroupValueType::Uint32: a.push_back(load(std::uint32_t{})); break;
      case GroupValueType::Uint64: a.push_back(load(std::uint64_t{})); break;
      case GroupValueType::Int8: a.push_back(load(std::int8_t{})); break;
      case GroupValueType::Int16: a.push_back(load(std::int16_t{})); break;
      case GroupValueType::Int32: a.push_back(load(std::int32_t{})); break;
      case GroupValueType::Int64: a.push_back(load(std::int64_t{})); break;
      case GroupValueType::Float16: a.push_back(half_to_float(load(std::uint16_t{}))); break;
      case GroupValueType::Float32: a.push_back(load(float{})); break;
      case GroupValueType::Float64: a.push_back(load(double{})); break;
    }
  }
  return a;
}

}  // namespace

void add_info_command(CLI::App& app) {
  struct Options {
    std::string file;
    bool json = false;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "info", "Summarise a .vxl file (opens and validates its tables, O(voxels)) or a .vxlz package (checks it whole)");
  cmd->add_option("file", opt->file, ".vxl file or .vxlz package")->required();
  cmd->add_flag("--json", opt->json, "print JSON instead of text");
  cmd->callback([opt] {
    if (starts_as_vxlz(opt->file)) {
      const nlohmann::json j = package_info(VxlzFile::open(opt->file));
      if (opt->json)
        std::printf("%s\n", j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
      else
        print_package_info(j);
      return;
    }
    VxlFile f = VxlFile::open(opt->file);
    const MetaSection& m = f.meta();
    nlohmann::json j;
    j["file"] = opt->file;
    add_meta_summary(f.header(), m, j);
    j["bytes"] = f.bytes().size();
    j["segments"] = m.segment_count;
    j["vertices"] = m.vertex_count;
    j["synthetic_points"] = m.synthetic_point_count;
    j["levels"] = std::max(m.level_count, 1u);  // of detail: 0 (every streamline) to levels - 1
    // Positions: the encoding and, when packed, the largest error any voxel allows (spec §5.4).
    j["positions"] = position_encoding_name(f.position_encoding());
    if (f.position_encoding() == PositionEncoding::Packed) {
      double bound = 0;
      for (const VoxelEntry& v : f.voxels()) bound = std::max(bound, packed_error_bound(v));
      j["position_error_bound_mm"] = bound;
    }
    nlohmann::json sections = nlohmann::json::array();
    for (const SectionEntry& e : f.sections())
      sections.push_back({{"id", std::string(e.id, 4)}, {"offset", e.offset}, {"bytes", e.size}});
    j["sections"] = sections;
    auto sets = [](const ValueSets& v) {
      nlohmann::json a = nlohmann::json::array();
      for (std::uint32_t k = 0; k < v.size(); ++k)
        a.push_back({{"name", v.name(k)}, {"min", v.min(k)}, {"max", v.max(k)}});
      return a;
    };
    j["vertex_values"] = sets(f.vertex_values());
    j["streamline_values"] = sets(f.streamline_values());
    nlohmann::json groups = nlohmann::json::array();
    for (const StreamlineGroup& g : f.groups())
      groups.push_back({{"name", g.name}, {"streamlines", g.members.size()}, {"values", nlohmann::json::array()}});
    for (const GroupValues& v : f.group_values())
      groups[v.group]["values"].push_back({{"name", v.name},
                                           {"dtype", group_value_type_name(v.type)},
                                           {"components", v.components},
                                           {"values", row_numbers(v)}});
    j["groups"] = groups;
    add_provenance_summary(parse_json(f.provenance_json(), f.path(), f.provenance_offset(), "PROV"), j);
    if (opt->json) {
      // open() has checked every name for UTF-8; replacing invalid bytes is the last line of defence.
      std::printf("%s\n", j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
      return;
    }
    std::printf("file          %s (.vxl %s, %llu bytes)\n", opt->file.c_str(), j["version"].get<std::string>().c_str(),
                (unsigned long long)f.bytes().size());
    print_source_line(j);
    std::printf("streamlines   %llu\npoints        %llu\nvoxels        %u (grid %d x %d x %d)\n",
                (unsigned long long)m.streamline_count, (unsigned long long)m.point_count, m.voxel_count,
                m.grid_dims[0], m.grid_dims[1], m.grid_dims[2]);
    std::printf("segments      %llu\nvertices      %llu (%llu points added at voxel faces)\n",
                (unsigned long long)m.segment_count, (unsigned long long)m.vertex_count,
                (unsigned long long)m.synthetic_point_count);
    std::printf("voxel size    %g mm%s\norders        %u stored (x2 by reversal)\n", m.voxel_size,
                j.contains("voxel_size_choice") ? (" (" + j["voxel_size_choice"].get<std::string>() + ")").c_str() : "",
                m.stored_order_count);
    const unsigned levels = j["levels"].get<unsigned>();
    if (levels > 1)
      std::printf("levels        %u of detail (0 to %u; level d keeps about 1/8^d of the streamlines)\n", levels,
                  levels - 1);
    else
      std::printf("levels        1 (full detail only)\n");
    if (j.contains("position_error_bound_mm"))
      std::printf("positions     packed (10 bits per axis per voxel; error at most %.3g um)\n",
                  1000 * j["position_error_bound_mm"].get<double>());
    else
      std::printf("positions     float32 (exact)\n");
    std::printf("bounds        [%.3f, %.3f, %.3f] .. [%.3f, %.3f, %.3f] mm\nsections     ", m.bounds_min[0],
                m.bounds_min[1], m.bounds_min[2], m.bounds_max[0], m.bounds_max[1], m.bounds_max[2]);
    for (const SectionEntry& e : f.sections()) std::printf(" %.4s:%llu", e.id, (unsigned long long)e.size);
    std::printf("\n");
    for (const char* kind : {"vertex_values", "streamline_values"})
      for (const auto& v : j[kind])
        std::printf("%-13s %s [%g, %g]\n", kind == std::string("vertex_values") ? "point values" : "streamline values",
                    v["name"].get<std::string>().c_str(), v["min"].is_number() ? v["min"].get<double>() : NAN,
                    v["max"].is_number() ? v["max"].get<double>() : NAN);
    for (const auto& g : j["groups"]) {
      std::printf("group         %s (%llu streamlines)\n", g["name"].get<std::string>().c_str(),
                  (unsigned long long)g["streamlines"].get<std::uint64_t>());
      for (const auto& v : g["values"]) {
        // At most 8 numbers a row: a long row (a matrix, a histogram) is there in full with --json.
        std::string numbers;
        const auto& row = v["values"];
        for (std::size_t i = 0; i < std::min<std::size_t>(row.size(), 8); ++i) numbers += " " + row[i].dump();
        if (row.size() > 8) numbers += " ...";
        std::printf("  values      %s (%s x %llu):%s\n", v["name"].get<std::string>().c_str(),
                    v["dtype"].get<std::string>().c_str(), (unsigned long long)v["components"].get<std::uint32_t>(),
                    numbers.c_str());
      }
    }
  });
}

}  // namespace vxl::cli
