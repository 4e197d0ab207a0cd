#include "convert.h"

#include <chrono>
#include <filesystem>

#include "segment_orders.h"
#include "vxl_writer.h"

#ifndef VOXLINES_VERSION
#define VOXLINES_VERSION "0.0.0"
#endif

namespace vxl {
namespace {

std::string provenance_json(const SourceInfo& src, const ConvertSettings& settings, unsigned threads) {
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
  j["converter"] = {{"name", "voxlines"}, {"version", VOXLINES_VERSION}, {"voxel_size", settings.voxel_size},
                    {"orders", settings.orders}, {"threads", threads}};
  j["warnings"] = src.warnings;
  // Invalid UTF-8 in a source header must not make the whole file unwritable: replace it.
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace

ConvertSummary convert_tractogram(Tractogram&& t, const std::string& out_path, const ConvertSettings& settings) {
  OrderSetSpec order_set = parse_order_set(settings.orders);
  const unsigned threads = resolve_threads(settings.threads);
  SourceInfo source = t.source;
  std::vector<GroupContent> groups;
  for (const StreamlineGroup& g : t.groups) groups.push_back({g.name, g.members});

  VoxelizeSettings vs;
  vs.voxel_size = settings.voxel_size;
  vs.threads = threads;
  vs.progress = settings.progress;
  using Clock = std::chrono::steady_clock;
  auto seconds_since = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  ConvertSummary summary;
  auto t0 = Clock::now();
  VoxelizedTractogram vt = voxelize(std::move(t), vs);
  summary.voxelize_seconds = seconds_since(t0);
  t0 = Clock::now();
  BuiltOrders orders = build_orders(vt, order_set, threads, settings.progress);
  summary.orders_seconds = seconds_since(t0);

  VxlContent c;
  c.meta = vt.meta;
  c.directions = orders.directions;
  c.voxels = vt.voxels;
  c.vertices = vt.vertices;
  c.orders = orders.bytes;
  c.voxlines = vt.voxlines;
  c.streamline_first_voxline = vt.streamline_first_voxline;
  c.provenance_json = provenance_json(source, settings, threads);
  c.groups = groups;
  if (settings.progress) settings.progress("writing", 0.0);
  t0 = Clock::now();
  write_vxl(out_path, c);
  summary.write_seconds = seconds_since(t0);
  if (settings.progress) settings.progress("writing", 1.0);

  const MetaSection& m = vt.meta;
  summary.streamlines = m.streamline_count;
  summary.points = m.point_count;
  summary.voxels = m.voxel_count;
  summary.vertices = m.vertex_count;
  summary.segments = m.segment_count;
  summary.synthetic_points = m.synthetic_point_count;
  return summary;
}

}  // namespace vxl
