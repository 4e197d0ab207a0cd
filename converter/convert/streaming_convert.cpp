#include "converter/convert/streaming_convert.h"

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <utility>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "converter/pipeline/streaming_conversion.h"
#include "converter/readers/source_formats.h"
#include "format/base/error.h"
#include "format/base/parallel.h"
#include "format/vxl_sections.h"
#include "format/vxl_value_sets.h"

namespace vxl {
namespace streaming {

void StreamingConversion::fail_changed() const {
  fail_input(job_.path, std::nullopt,
             "the file changed while it was being converted (--memory-limit reads it several times)");
}

void StreamingConversion::check_source_type() const {
  if (job_.held) return;
  const SourceMatch match = source_format_of(job_.path);
  if (!match.format || !match.format->streamable)
    fail_unsupported(job_.path, "--memory-limit streams TCK sources only (.tck); convert " +
                                    std::string(match.format ? match.format->name : "other") + " sources without it");
}

void StreamingConversion::open_stream() {
  if (!job_.held) {
    reader_ = std::make_unique<BatchReader>(job_.path, budget_, job_.threads, job_.settings.progress);
    return;
  }
  const ReadPlan plan = plan_reading(budget_);
  reader_ = std::make_unique<BatchReader>(std::make_unique<TractogramBatchSource>(*job_.held, plan.batch_points), plan,
                                          budget_, job_.threads, job_.settings.progress);
}

// The held source's per-point values, spread over the vertices as they are placed: VVAL's payload, held whole
// (the arrays of all sets follow one another in it, so no range's part of them could be written alone). Checks
// that every value set has a value per point or streamline.
void StreamingConversion::plan_vertex_values() {
  if (!job_.held) return;
  const Tractogram& t = *job_.held;
  // convert_tractogram refuses such sources (prepare_value_sets): a caller that did not check has a bug.
  for (const ValueSet& v : t.point_values)
    if (v.values.size() != t.point_count()) throw std::logic_error("convert_streaming: not a value per point");
  for (const ValueSet& v : t.streamline_values)
    if (v.values.size() != t.streamline_count())
      throw std::logic_error("convert_streaming: not a value per streamline");
  const std::vector<ValueSet>& sets = t.point_values;
  if (sets.empty()) return;
  const std::uint64_t bytes = value_sets_bytes(sets.size(), table_.meta.vertex_count);
  budget_.track(bytes, vertex_values_held_, [] { return "the per-point values spread over the vertices"; });
  vertex_values_.assign(bytes, 0);
  std::vector<std::string> names;
  for (const ValueSet& v : sets) names.push_back(v.name);
  vertex_value_arrays_ = layout_value_sets(vertex_values_, names, table_.meta.vertex_count);
}

// The held source's sections besides the blocks and tables: VVAL (placed), SVAL, GRPS and GDAT.
void StreamingConversion::write_held_extras() {
  if (!job_.held) return;
  const Tractogram& t = *job_.held;
  if (!vertex_values_.empty()) {
    finish_value_sets(vertex_values_);
    out_->append(VxlStreamWriter::kVval, vertex_values_);
    vertex_value_arrays_.clear();
    std::vector<std::uint8_t>().swap(vertex_values_);
    budget_.shrink(0, vertex_values_held_);
  }
  if (!t.streamline_values.empty()) {
    std::vector<std::uint8_t> payload(value_sets_bytes(t.streamline_values.size(), t.streamline_count()), 0);
    std::vector<std::string> names;
    for (const ValueSet& v : t.streamline_values) names.push_back(v.name);
    const std::vector<std::span<float>> arrays = layout_value_sets(payload, names, t.streamline_count());
    for (std::size_t k = 0; k < arrays.size(); ++k)
      std::copy(t.streamline_values[k].values.begin(), t.streamline_values[k].values.end(), arrays[k].begin());
    finish_value_sets(payload);
    out_->append(VxlStreamWriter::kSval, payload);
  }
  if (!t.groups.empty()) out_->append(VxlStreamWriter::kGrps, encode_groups(t.groups));
  if (!t.group_values.empty()) out_->append(VxlStreamWriter::kGdat, encode_group_values(t.group_values));
}

// The output's section sizes: the voxel table's counts, and a held source's value sets and groups.
VxlSectionSizes StreamingConversion::output_sizes(std::uint64_t provenance_bytes) const {
  if (!job_.held) return section_sizes(table_.meta, table_.order_bytes, provenance_bytes, 0);
  const Tractogram& t = *job_.held;
  VxlSectionSizes sizes = section_sizes(
      table_.meta, table_.order_bytes, provenance_bytes, t.groups.empty() ? 0 : encode_groups(t.groups).size(),
      static_cast<std::uint32_t>(t.point_values.size()), static_cast<std::uint32_t>(t.streamline_values.size()));
  if (!t.group_values.empty()) sizes.group_values = encode_group_values(t.group_values).size();
  return sizes;
}

void StreamingConversion::write_rest() {
  out_->append_meta(table_.meta);
  std::vector<DirectionEntry> directions = order_directions(job_.order_set);
  out_->append_items<DirectionEntry>(VxlStreamWriter::kDirs, directions);
  if (job_.order_set.per_voxel()) {  // VDIR, a function of (seed, voxel coordinate): made in bounded slices
    const std::size_t slice = 4096;
    std::vector<DirectionEntry> voxel_directions;
    for (std::size_t first = 0; first < table_.voxels.size(); first += slice) {
      const std::span<const VoxelEntry> part =
          std::span<const VoxelEntry>(table_.voxels).subspan(first, std::min(slice, table_.voxels.size() - first));
      voxel_directions.resize(part.size() * directions.size());
      fill_voxel_directions(job_.order_set, part, voxel_directions);
      out_->append_items<DirectionEntry>(VxlStreamWriter::kVdir, voxel_directions);
    }
  }
  out_->append_items<VoxelEntry>(VxlStreamWriter::kVoxt, table_.voxels);
  if (!table_.levels.empty()) out_->append_items<LevelEntry>(VxlStreamWriter::kLods, table_.levels);
}

// The voxel index's lists are filled as the first range is placed where the plan leaves room for them: the write
// stage then writes them instead of reading VXLN and STRM back (twice) to sort them.
void StreamingConversion::plan_index_lists() {
  const std::uint64_t bytes = VoxelIndexLists::bytes(table_.voxels.size(), table_.meta.voxline_count);
  if (!plan_voxel_index_lists(budget_, plan_, bytes)) return;
  table_.index_lists_held = bytes;
  std::vector<std::uint64_t> voxlines(table_.voxels.size());
  for (std::size_t g = 0; g < voxlines.size(); ++g)  // each voxline has one vertex more than it has segments
    voxlines[g] = table_.voxels[g].vertex_count - table_.voxels[g].segment_count;
  table_.index_lists.emplace(voxlines);
  summary_.voxel_index_while_placing = true;
}

ConvertSummary StreamingConversion::run() {
  if (job_.settings.memory_limit == 0) throw std::logic_error("convert_streaming: memory_limit must be > 0");
  check_source_type();
  job_.order_set = parse_order_set(job_.settings.orders);
  job_.threads = resolve_threads(job_.settings.threads);
  if (!job_.settings.voxel_size_auto) detail::check_voxel_size(job_.settings.voxel_size, job_.path);
  detail::check_level_count(job_.settings.levels, job_.path);
  summary_.passes = 0;

  auto t0 = Clock::now();
  open_stream();
  scan();
  summary_.read_seconds = seconds_since(t0);

  t0 = Clock::now();
  count_voxels();
  build_table();
  summary_.voxelize_seconds = seconds_since(t0);
  plan_vertex_values();
  // Planned without the voxel runs, which are kept for the placing passes only where the plan leaves room.
  budget_.shrink(0, table_.runs_held);
  plan_ =
      plan_conversion(budget_, {table_.meta, table_.voxels, table_.levels, job_.settings.levels,
                                job_.settings.positions, table_.order_bytes, job_.threads, reader_->plan().batch_points,
                                job_.tuning.order_chunk_bytes, job_.tuning.range_bytes, job_.tuning.vertex_blocks});
  table_.runs_kept = counting_.recording_runs && plan_voxel_runs(budget_, plan_, table_.runs.bytes());
  if (table_.runs_kept)
    table_.runs_held = table_.runs.bytes();
  else
    table_.runs.clear();
  plan_index_lists();
  staged_held_ = plan_.staged_bytes;
  table_.spans.resize(table_.meta.streamline_count);
  if (plan_.block_staging_bytes > 0) {
    void* p = std::aligned_alloc(DirectRegionWriter::kBlock, plan_.pool_bytes);
    if (p == nullptr) throw std::bad_alloc();
    pool_.reset(static_cast<std::uint8_t*>(p));
  }
  const std::vector<VoxelRange>& ranges = plan_.ranges;

  const std::string provenance = provenance_json(reader_->source(), job_.settings, job_.voxel_size_choice);
  out_ = std::make_unique<VxlStreamWriter>(job_.out_path, output_sizes(provenance.size()), plan_.direct_staging_bytes);
  for (std::size_t k = 0; k < ranges.size(); ++k) {
    build_range(ranges[k], k, ranges.size());
#if defined(__GLIBC__)
    malloc_trim(0);  // give back what the range freed, lest the allocator keep it resident for the next one
#endif
  }

  summary_.voxelised_once = table_.runs_kept;
  table_.runs.clear();
  budget_.shrink(0, table_.runs_held);

  report("writing", 0.0);
  t0 = Clock::now();
  write_rest();
  if (!summary_.voxel_index_while_placing) {
    // The voxel index's buffer takes the memory the ranges and the pool gave back: the pool itself where it is
    // large enough (its pages are in memory already; fresh ones cost more than the sorting on some machines).
    std::span<std::uint8_t> index_buffer;
    if (pool_ && plan_.pool_bytes >= plan_.voxel_index_buffer_bytes)
      index_buffer = {pool_.get(), plan_.voxel_index_buffer_bytes};
    else
      pool_.reset();
    out_->append_voxel_index(plan_.voxel_index_buffer_bytes, index_buffer);
  }
  pool_.reset();
  if (!scan_.lengths.empty()) out_->append_items<float>(VxlStreamWriter::kSlen, scan_.lengths);
  write_held_extras();
  out_->append(VxlStreamWriter::kProv, {reinterpret_cast<const std::uint8_t*>(provenance.data()), provenance.size()});
  out_->commit();
  summary_.write_seconds += seconds_since(t0);
  report("writing", 1.0);

  summary_.take_counts(table_.meta);
  summary_.passes = reader_->passes();
  summary_.partitions = ranges.size();
  summary_.vertices_read_back = plan_.block_staging_bytes > 0;
  for (const VoxelRange& r : ranges) summary_.partition_starts.push_back(r.first);
  if (!job_.held) summary_.warnings = reader_->source().warnings;  // a held source's are its reader's to show
  return summary_;
}

}  // namespace streaming

ConvertSummary convert_streaming(const std::string& source_path, const std::string& out_path,
                                 const ConvertSettings& settings) {
  return convert_streaming(source_path, out_path, settings, StreamingTuning{});
}

ConvertSummary convert_streaming(const Tractogram& held, const std::string& out_path, const ConvertSettings& settings,
                                 const StreamingTuning& tuning) {
  streaming::StreamingConversion conversion(held, out_path, settings, tuning);
  return conversion.run();
}

ConvertSummary convert_streaming(const std::string& source_path, const std::string& out_path,
                                 const ConvertSettings& settings, const StreamingTuning& tuning) {
  streaming::StreamingConversion conversion(source_path, out_path, settings, tuning);
  return conversion.run();
}

}  // namespace vxl
