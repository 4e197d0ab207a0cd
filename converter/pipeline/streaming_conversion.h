// The conversion within a memory limit (streaming_convert.h), in stages that share this class: the scan and
// the voxel counts (voxel_counting.cpp), the plan (conversion_plan.h), each range's placing pass
// (range_placement.cpp) and its orders (range_orders.h); streaming_convert.cpp runs them. Internal to
// those files.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "converter/convert/convert.h"
#include "converter/convert/position_packing.h"
#include "converter/convert/segment_orders.h"
#include "converter/convert/voxel_table.h"
#include "converter/convert/voxelize.h"
#include "converter/convert/voxelize_streamline.h"
#include "converter/pipeline/batch_reader.h"
#include "converter/pipeline/conversion_plan.h"
#include "converter/pipeline/memory_budget.h"
#include "converter/pipeline/range_orders.h"
#include "converter/pipeline/table_appender.h"
#include "converter/pipeline/vertex_sink.h"
#include "converter/pipeline/voxel_runs.h"
#include "format/base/direct_region_writer.h"
#include "format/base/direct_write_queue.h"
#include "format/voxel_voxlines.h"
#include "format/vxl_positions.h"
#include "format/vxl_stream_writer.h"

namespace vxl::streaming {

using detail::Grid;
using detail::kNoSynthetic;
using detail::TempVoxline;
using detail::VoxelIndex;
using Clock = std::chrono::steady_clock;

// The parts a batch is cut in, of about as many points each, for the reader's threads (BatchReader::
// each_batch). More parts than two cores keep both busy beside the read; the counting and the placing
// passes cut alike (the placing passes find the counting pass's voxel runs by the parts' first streamlines).
inline constexpr std::size_t kBatchParts = 3;
using BatchCut = std::array<std::uint64_t, kBatchParts + 1>;  // part p: streamlines [cut[p], cut[p + 1])

inline BatchCut cut_batch(const Tractogram& b) {
  const std::uint64_t n = b.streamline_count(), points = b.point_count();
  BatchCut cut{};
  for (std::size_t p = 1; p < kBatchParts; ++p) {
    const std::uint64_t at =
        std::upper_bound(b.offsets.begin(), b.offsets.end(), points / kBatchParts * p) - b.offsets.begin() - 1;
    cut[p] = std::clamp(at, cut[p - 1], n);
  }
  cut[kBatchParts] = n;
  return cut;
}

inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Where voxelize_streamline puts the voxlines of one streamline (or of several, one after the other).
template <typename Index>
struct SinkOf {
  Index index;
  std::vector<TempVoxline> voxlines;
  std::vector<float> synthetic_xyz;
  std::vector<double> synthetic_t;  // where each added point lies on its step: per-point values are interpolated there
  bool too_many_synthetic = false;
  void clear() {
    voxlines.clear();
    synthetic_xyz.clear();
    synthetic_t.clear();
  }
  std::uint64_t bytes() const {
    return voxlines.capacity() * sizeof(TempVoxline) + synthetic_xyz.capacity() * sizeof(float) +
           synthetic_t.capacity() * sizeof(double);
  }
};

using Sink = SinkOf<VoxelIndex>;

// What the conversion was asked to do.
struct StreamingJob {
  std::string path, out_path;
  // A source already in memory (convert_tractogram), read batch by batch from there; its value sets and
  // groups are written too. Null: the TCK file at `path`, read a part at a time.
  const Tractogram* held = nullptr;
  ConvertSettings settings;  // its voxel_size chosen by the scan under --voxel-size auto
  StreamingTuning tuning;
  OrderSetSpec order_set;
  unsigned threads = 1;           // resolved
  std::string voxel_size_choice;  // --voxel-size auto's reason, once the scan has chosen
};

// What pass 1 found: the bounds of every point, the longest step (squared) and each streamline's length
// (SLEN, written at the end; 4 bytes a streamline, held against the memory limit).
struct SourceScan {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double longest_step2 = 0;
  std::vector<float> lengths;
  std::uint64_t lengths_held = 0;  // as taken from the budget
};

// Pass 2's counts and tight bounds per voxel (by local id), until build_table makes the voxel table of them.
struct CountingState {
  detail::VoxelUse use;
  detail::VoxelBounds bounds;
  std::uint64_t sink_held = 0, table_held = 0;  // as taken from the budget
  bool recording_runs = true;                   // into StreamedVoxelTable::runs, until the budget wants their memory
};

// The voxel table, and what maps the source's voxels and streamlines onto it, from pass 2 on.
struct StreamedVoxelTable {
  MetaSection meta{};
  Grid grid{};
  std::uint64_t synthetic_limit = 0;     // points added at voxel faces, at most
  Sink sink;                             // the source's voxel index (local ids)
  std::vector<std::uint32_t> global_id;  // local id -> voxel index
  std::vector<VoxelEntry> voxels;
  std::vector<LevelEntry> levels;  // LODS, voxel-major
  // By (local id * levels + depth): the next vertex of its voxel to place for that depth (global index).
  std::vector<std::uint64_t> cursor;
  std::uint64_t order_bytes = 0;
  // Per streamline: its lowest and highest voxel index (set by the first range's pass), so that later
  // passes skip the streamlines that have no voxel in their range.
  std::vector<std::array<std::uint32_t, 2>> spans;
  // Every streamline's voxlines as pass 2 found them (empty when the limit leaves no room for them: the
  // placing passes voxelise again), and what the budget counts of them.
  VoxelRuns runs;
  std::uint64_t runs_held = 0;
  bool runs_kept = false;  // for the placing passes
  // The voxel index's lists, filled by the first range's placing when the plan holds them and written at its end
  // (else empty: the write stage sorts them from the tables read back), and what the budget counts of them.
  std::optional<VoxelIndexLists> index_lists;
  std::uint64_t index_lists_held = 0;
};

// One conversion within a memory limit: run() reads the source with a BatchReader, scans it (scan), counts
// its voxels (count_voxels) into the voxel table (build_table), plans the rest (plan_conversion), then
// builds each range (build_range: place_range, then write_orders) and writes the tables (write_rest).
class StreamingConversion {
 public:
  StreamingConversion(const std::string& source, const std::string& out, const ConvertSettings& settings,
                      const StreamingTuning& tuning)
      : job_{source, out, nullptr, settings, tuning, {}, 1, {}}, budget_(settings.memory_limit, source) {}
  StreamingConversion(const Tractogram& held, const std::string& out, const ConvertSettings& settings,
                      const StreamingTuning& tuning)
      : job_{held.source.path, out, &held, settings, tuning, {}, 1, {}},
        budget_(settings.memory_limit, held.source.path) {}

  ConvertSummary run();

 private:
  void check_source_type() const;
  void open_stream();
  void scan();
  void count_voxels();
  struct PlanPart;
  std::vector<std::uint32_t> fold_into_first(PlanPart& main, const PlanPart& other) const;
  struct PendingRuns;
  void append_runs(PendingRuns& pending);
  void hold_runs(std::span<PlanPart, kBatchParts> parts, PendingRuns& pending);
  void drop_runs();
  void build_table();
  void plan_index_lists();
  void build_range(const VoxelRange& r, std::size_t index, std::size_t count);
  void count_part(const Tractogram& b, std::uint64_t first, std::uint64_t begin, std::uint64_t end,
                  std::uint64_t points, std::uint64_t synthetic, std::uint64_t most_voxels, std::uint64_t other_voxels,
                  PlanPart& part) const;
  struct StagedPart;
  struct RangePlacement;
  void place_range(const VoxelRange& r, bool tables, const std::string& of, std::span<std::uint8_t> window);
  std::vector<std::uint64_t> block_ends(const VoxelRange& r) const;
  VertexSink open_vertex_sink(std::span<std::uint8_t> window, std::span<const std::uint64_t> ends) const;
  void stage_part(const RangePlacement& placing, const Tractogram& b, std::uint64_t first, std::uint64_t begin,
                  std::uint64_t end, StagedPart& part) const;
  void place_part(RangePlacement& placing, const StagedPart& part, int half);
  void index_part(const StagedPart& part);
  void cut_by_runs(std::uint64_t first_point, std::uint64_t points, std::uint64_t& run,
                   std::vector<TempVoxline>& out) const;
  void write_orders(const VoxelRange& r, std::span<const std::uint8_t> range_vertices, const std::string& stage);
  bool packed() const { return job_.settings.positions == PositionEncoding::Packed; }
  // Where voxel i's orders start in ORDB (i = voxel count: the payload's end).
  std::uint64_t orders_start(std::size_t i) const { return vxl::orders_start(table_.voxels, table_.order_bytes, i); }
  void write_rest();
  // The held source's per-point values (VVAL), placed with the vertices: the payload, held whole.
  void plan_vertex_values();
  void stage_values(const StagedPart& part, std::span<const TempVoxline> streamline, std::size_t j, std::uint64_t used,
                    std::uint64_t point_base, std::vector<float>& out) const;
  void write_held_extras();
  VxlSectionSizes output_sizes(std::uint64_t provenance_bytes) const;
  [[noreturn]] void fail_changed() const;
  void report(const std::string& stage, double fraction) const {
    if (job_.settings.progress) job_.settings.progress(stage.c_str(), fraction);
  }

  StreamingJob job_;
  MemoryBudget budget_;
  ConvertSummary summary_;
  std::unique_ptr<BatchReader> reader_;
  SourceScan scan_;                // pass 1
  CountingState counting_;         // pass 2, until the table is built
  StreamedVoxelTable table_;       // pass 2 on
  ConversionPlan plan_;            // once the voxel table is built
  std::uint64_t staged_held_ = 0;  // the staged parts of two batches, as taken from the budget
  // Written block by block: one buffer for the blocks' staging while they are placed, then for the
  // orders' chunks and the vertices read back (fresh pages are dear: a buffer reused is not faulted in
  // again).
  std::unique_ptr<std::uint8_t, void (*)(void*)> pool_{nullptr, std::free};
  VoxlineEnds ends_;  // float32 positions: the voxline ends of the range being built
  // The held source's per-point values spread over the vertices (VVAL's payload) and its arrays, one per set.
  std::vector<std::uint8_t> vertex_values_;
  std::vector<std::span<float>> vertex_value_arrays_;
  std::uint64_t vertex_values_held_ = 0;  // as taken from the budget
  std::unique_ptr<VxlStreamWriter> out_;
};

// One voxline's vertices staged for a placing half: its (voxel, level) block and how many vertices.
struct StagedVoxline {
  std::uint32_t voxel;  // local id
  std::uint32_t count;
  std::uint32_t depth;
};

// Part of a batch voxelised on its own thread (stage_part), waiting to be placed in order: what each placing
// half places, in streamline order, and (first range) the part's table entries.
struct StreamingConversion::StagedPart {
  std::uint64_t begin = 0, end = 0;                    // streamlines of the batch
  std::uint64_t source_first = 0;                      // the index of streamline `begin` in the source
  SinkOf<detail::SharedVoxelIndex> sink;               // the voxlines of the streamline being staged
  std::array<std::vector<StagedVoxline>, 2> voxlines;  // per half: the voxlines in range, in order
  std::array<std::vector<std::uint32_t>, 2> words;     // packed: per half, those voxlines' vertices in order
  std::array<std::vector<float>, 2> xyz;               // float32: the same
  // A held source's per-point values: per half, each staged voxline's values of every set, set after set.
  std::array<std::vector<float>, 2> values;
  // First range: every voxline's VXLN entry and each streamline's voxline count and lowest and highest voxel.
  std::vector<VoxlineEntry> table_entries;
  std::vector<std::uint32_t> streamline_voxlines;
  std::vector<std::array<std::uint32_t, 2>> spans;
  std::uint64_t bytes() const {
    std::uint64_t b = sink.bytes() + table_entries.capacity() * sizeof(VoxlineEntry) +
                      streamline_voxlines.capacity() * sizeof(std::uint32_t) +
                      spans.capacity() * sizeof(std::array<std::uint32_t, 2>);
    for (int h = 0; h < 2; ++h)
      b += voxlines[h].capacity() * sizeof(StagedVoxline) + words[h].capacity() * sizeof(std::uint32_t) +
           (xyz[h].capacity() + values[h].capacity()) * sizeof(float);
    return b;
  }
};

// What one range's placing pass keeps between batches.
struct StreamingConversion::RangePlacement {
  RangePlacement(const VoxelRange& r, bool first_range, VertexSink&& vertex_sink)
      : range(r), tables(first_range), sink(std::move(vertex_sink)) {}
  const VoxelRange& range;
  bool tables;                        // the first range: also the voxline and streamline tables
  VertexSink sink;                    // where the range's vertices go (blocks by local voxel id * levels + level)
  std::vector<VertexPacker> packers;  // by voxel - range.first (packed positions)
  std::optional<TableAppender> table_appender;  // the first range's VXLN and STRM
  std::uint64_t voxline_index = 0, streamlines = 0;
  std::size_t split = 0;  // the first voxel of the second placing half (range.end: placed whole)
  // By (local id * levels + depth), for the range's voxels: where the block ends (its last vertex + 1).
  std::vector<std::uint64_t> block_end;
  std::array<StagedPart, kBatchParts> parts[2];  // two sets of a batch's parts: one being staged, one being placed
};

// Part of a batch counted on its own thread in pass 2 (count_part).
struct StreamingConversion::PlanPart {
  Sink sink;
  detail::VoxelUse use;
  detail::VoxelBounds bounds;
  std::uint64_t voxlines = 0, synthetic = 0;  // in the batch being counted
  std::vector<VoxelRun> runs;                 // of the batch being counted (local ids of `sink`'s index)
};

// A batch's voxel runs as pass 2 counted them, waiting to be appended to table_.runs (append_runs) while the next
// batch is counted: each part's list, its first streamline in the source and (parts past the first) its local ids in
// the first part's index.
struct StreamingConversion::PendingRuns {
  std::array<std::vector<VoxelRun>, kBatchParts> runs;
  std::array<std::uint64_t, kBatchParts> first{};
  std::array<std::vector<std::uint32_t>, kBatchParts> local_ids;
  bool waiting = false;
};

}  // namespace vxl::streaming
