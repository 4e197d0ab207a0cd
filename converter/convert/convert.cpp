#include "converter/convert/convert.h"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "converter/convert/segment_orders.h"
#include "converter/convert/voxel_size_auto.h"
#include "converter/convert/voxel_table.h"
#include "format/base/error.h"
#include "format/base/parallel.h"
#include "format/vxl_value_sets.h"
#include "format/vxl_writer.h"

namespace vxl {

std::string provenance_json(const SourceInfo& src, const ConvertSettings& settings, unsigned threads,
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
                    {"levels", settings.levels},
                    {"threads", threads}};
  if (!voxel_size_choice.empty()) j["converter"]["voxel_size_auto"] = voxel_size_choice;
  j["warnings"] = src.warnings;
  if (!src.value_files.empty()) j["value_files"] = src.value_files;
  // Invalid UTF-8 in a source header must not make the whole file unwritable: replace it.
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

namespace {

template <typename T>
std::span<std::uint8_t> bytes_of(std::span<T> s) {
  return {reinterpret_cast<std::uint8_t*>(s.data()), s.size_bytes()};
}

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
  ConvertSettings settings = given;
  OrderSetSpec order_set = parse_order_set(settings.orders);
  const unsigned threads = resolve_threads(settings.threads);
  std::string voxel_size_choice;
  if (settings.voxel_size_auto) {
    // One extra pass over the points (the voxeliser scans them again for its own bounds).
    detail::BoundsScan scan;
    scan.add(t.positions.data(), t.offsets.data(), 0, t.streamline_count(), 0);
    scan.check(t.source.path);
    const double lo[3] = {scan.lo[0], scan.lo[1], scan.lo[2]}, hi[3] = {scan.hi[0], scan.hi[1], scan.hi[2]};
    const VoxelSizeChoice choice = choose_voxel_size(t.point_count(), lo, hi, scan.rms_step(), t.source.path);
    settings.voxel_size = choice.size;
    voxel_size_choice = choice.reason;
  }
  // Warnings of the conversion itself: in PROV with the reader's, and in the summary for the caller to show.
  std::vector<std::string> warnings = prepare_value_sets(t);
  // PROV and GRPS are known before any work: their sizes go into the plan of the output file.
  const std::string provenance = provenance_json(t.source, settings, threads, voxel_size_choice);
  std::vector<std::uint8_t> groups_bytes;
  if (!t.groups.empty()) groups_bytes = encode_groups(t.groups);
  std::vector<std::uint8_t> group_values_bytes;
  if (!t.group_values.empty()) group_values_bytes = encode_group_values(t.group_values);

  VoxelizeSettings vs;
  vs.voxel_size = settings.voxel_size;
  vs.threads = threads;
  vs.levels = settings.levels;
  vs.progress = settings.progress;
  vs.pack_positions = settings.positions == PositionEncoding::Packed;
  using Clock = std::chrono::steady_clock;
  auto seconds_since = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  ConvertSummary summary;
  summary.warnings = std::move(warnings);
  auto t0 = Clock::now();

  // Pass 1 fixes every size; the output is then mapped and filled in place (no copies of the sections).
  VoxelPlan plan = plan_voxels(t, vs);
  MetaSection meta = plan.meta();
  meta.stored_order_count = static_cast<std::uint32_t>(order_set.directions.size());
  meta.order_set = static_cast<std::uint32_t>(order_set.kind);
  meta.position_encoding = static_cast<std::uint32_t>(settings.positions);
  const bool packed = settings.positions == PositionEncoding::Packed;
  const std::uint32_t levels = settings.levels;
  const std::uint64_t order_bytes = layout_orders(plan.voxels(), plan.levels(), levels, meta.stored_order_count);
  std::vector<std::string> point_set_names, streamline_set_names;
  for (const ValueSet& v : t.point_values) point_set_names.push_back(v.name);
  for (const ValueSet& v : t.streamline_values) streamline_set_names.push_back(v.name);
  VxlSectionSizes sizes = section_sizes(meta, order_bytes, provenance.size(), groups_bytes.size(),
                                        static_cast<std::uint32_t>(point_set_names.size()),
                                        static_cast<std::uint32_t>(streamline_set_names.size()));
  sizes.group_values = group_values_bytes.size();
  VxlWriter out(out_path, sizes);
  // Per-streamline values are copied as they are; per-point ones are spread over the vertices below.
  const auto streamline_arrays =
      layout_value_sets(out.streamline_values(), streamline_set_names, meta.streamline_count);
  for (std::size_t k = 0; k < streamline_arrays.size(); ++k)
    std::copy(t.streamline_values[k].values.begin(), t.streamline_values[k].values.end(), streamline_arrays[k].begin());
  t.streamline_values.clear();
  finish_value_sets(out.streamline_values());
  // Pass 2 writes all over these: fault them in first, in bulk (ORDB waits until the source is freed).
  // Packed positions are packed as they are placed (pass 1 found the voxels' bounds), and the orders are
  // built from the words: no float copy of the blocks.
  for (std::span<std::uint8_t> s : {bytes_of(out.float_vertices()), bytes_of(out.packed_vertices()),
                                    bytes_of(out.voxlines()), bytes_of(out.streamline_first_voxline())})
    prefault_for_write(s, threads);
  std::copy(plan.streamline_lengths().begin(), plan.streamline_lengths().end(), out.streamline_lengths().begin());
  VoxelBlocks blocks{
      out.voxels(), out.levels(), out.float_vertices(), out.voxlines(), out.streamline_first_voxline(), {}, {}};
  if (packed) blocks.packed_vertices = out.packed_vertices();
  blocks.vertex_values = layout_value_sets(out.vertex_values(), point_set_names, meta.vertex_count);
  VoxlineEnds ends = place_vertices(std::move(plan), std::move(t), blocks);
  finish_value_sets(out.vertex_values());
  summary.voxelize_seconds = seconds_since(t0);

  t0 = Clock::now();
  // What is final now goes to the disk while the orders are built (the write waits on the disk, not on a core).
  BackgroundTask<> written([&] {
    for (std::span<std::uint8_t> s :
         {bytes_of(out.voxels()), bytes_of(out.levels()), bytes_of(out.float_vertices()),
          bytes_of(out.packed_vertices()), bytes_of(out.voxlines()), bytes_of(out.streamline_first_voxline()),
          out.vertex_values(), out.streamline_values()})
      out.write_now(s);
  });
  prefault_for_write(out.orders(), threads);
  if (packed)
    build_orders_into_packed(out.voxels(), out.levels(), levels, out.packed_vertices(), order_set, out.orders(),
                             threads, settings.progress);
  else
    build_orders_into(out.voxels(), out.levels(), levels, out.float_vertices(), ends, order_set, out.orders(), threads,
                      settings.progress);
  written.get();
  summary.orders_seconds = seconds_since(t0);

  if (settings.progress) settings.progress("writing", 0.0);
  t0 = Clock::now();
  out.set_meta(meta);
  std::vector<DirectionEntry> directions = order_directions(order_set);
  std::copy(directions.begin(), directions.end(), out.directions().begin());
  fill_voxel_directions(order_set, out.voxels(), out.voxel_directions());
  std::copy(provenance.begin(), provenance.end(), out.provenance().begin());
  std::copy(groups_bytes.begin(), groups_bytes.end(), out.groups().begin());
  std::copy(group_values_bytes.begin(), group_values_bytes.end(), out.group_values().begin());
  out.commit(threads);
  summary.write_seconds = seconds_since(t0);
  if (settings.progress) settings.progress("writing", 1.0);

  summary.take_counts(meta);
  return summary;
}

}  // namespace vxl
