#include "converter/streaming_convert.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <span>
#include <utility>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "converter/pipeline/batch_reader.h"
#include "converter/pipeline/conversion_plan.h"
#include "converter/pipeline/memory_budget.h"
#include "converter/readers/source_formats.h"
#include "converter/readers/tck_stream.h"
#include "converter/segment_orders.h"
#include "converter/voxel_size_auto.h"
#include "converter/voxel_table.h"
#include "converter/voxelize.h"
#include "format/error.h"
#include "format/parallel.h"
#include "format/vxl_positions.h"
#include "format/vxl_stream_writer.h"

namespace vxl {
namespace {

using detail::Grid;
using detail::kNoSynthetic;
using detail::TempVoxline;
using detail::VoxelIndex;
using Clock = std::chrono::steady_clock;

// Where a batch is cut into two parts of about as many points each, for two threads: streamlines
// [cut[0], cut[1]) and [cut[1], cut[2]).
std::array<std::uint64_t, 3> two_parts(const Tractogram& b) {
  const std::uint64_t n = b.streamline_count();
  const std::uint64_t half =
      std::upper_bound(b.offsets.begin(), b.offsets.end(), b.point_count() / 2) - b.offsets.begin() - 1;
  return {0, std::min(half, n), n};
}

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Where voxelize_streamline puts the voxlines of one streamline (or of several, one after the other).
template <typename Index>
struct SinkOf {
  Index index;
  std::vector<TempVoxline> voxlines;
  std::vector<float> synthetic_xyz;
  bool too_many_synthetic = false;
  std::uint64_t bytes() const {
    return voxlines.capacity() * sizeof(TempVoxline) + synthetic_xyz.capacity() * sizeof(float);
  }
};

using Sink = SinkOf<VoxelIndex>;

class StreamingConversion {
 public:
  StreamingConversion(const std::string& source, const std::string& out, const ConvertSettings& settings,
                      const StreamingTuning& tuning)
      : path_(source), out_path_(out), settings_(settings), tuning_(tuning), budget_(settings.memory_limit, source) {}

  ConvertSummary run();

 private:
  void check_source_type() const;
  void open_stream();
  void scan();
  void plan();
  void build_table();
  void build_range(const VoxelRange& r, std::size_t index, std::size_t count);
  struct PlanPart;
  void count_part(const Tractogram& b, std::uint64_t first, std::uint64_t begin, std::uint64_t end,
                  std::uint64_t points, std::uint64_t synthetic, std::uint64_t most_voxels, std::uint64_t other_voxels,
                  PlanPart& part) const;
  struct StagedPart;
  struct RangePlacement;
  void place_range(const VoxelRange& r, bool tables, const std::string& of, std::span<std::uint8_t> window);
  void open_block_writers(RangePlacement& placing) const;
  void stage_part(const RangePlacement& placing, const Tractogram& b, std::uint64_t first, std::uint64_t begin,
                  std::uint64_t end, StagedPart& part) const;
  void place_part(RangePlacement& placing, const StagedPart& part);
  void write_orders(const VoxelRange& r, std::span<const std::uint8_t> range_vertices, const std::string& stage);
  void write_voxel_orders(const VoxelRange& r, std::size_t g, std::span<const std::uint8_t> vertices,
                          std::uint64_t vertices_first, VoxelOrderWriter& writer, VoxlineEnds& block_ends,
                          std::uint8_t* dst);
  bool packed() const { return settings_.positions == PositionEncoding::Packed; }
  // Where voxel i's orders start in ORDR (i = voxel count: the payload's end).
  std::uint64_t orders_start(std::size_t i) const { return vxl::orders_start(voxels_, order_bytes_, i); }
  void write_rest();
  [[noreturn]] void fail_changed() const;
  void report(const std::string& stage, double fraction) const {
    if (settings_.progress) settings_.progress(stage.c_str(), fraction);
  }

  std::string path_, out_path_;
  ConvertSettings settings_;
  StreamingTuning tuning_;
  std::string voxel_size_choice_;  // --voxel-size auto's reason, once scan() has chosen
  MemoryBudget budget_;
  OrderSetSpec order_set_;
  unsigned threads_ = 1;
  ConvertSummary summary_;

  std::unique_ptr<BatchReader> reader_;

  // pass 1
  double lo_[3] = {INFINITY, INFINITY, INFINITY}, hi_[3] = {-INFINITY, -INFINITY, -INFINITY};
  double longest_step2_ = 0;
  // pass 2 and the table
  MetaSection meta_{};
  Grid grid_{};
  std::uint64_t synthetic_limit_ = 0;
  Sink sink_;
  std::uint64_t sink_held_ = 0, plan_held_ = 0, staged_held_ = 0;
  detail::VoxelUse use_;                  // by local id, while planning
  detail::VoxelBounds bounds_;            // by local id, while planning
  std::vector<std::uint32_t> global_id_;  // local id -> voxel index
  std::vector<VoxelEntry> voxels_;
  std::vector<LevelEntry> levels_;  // LODS, voxel-major
  // By (local id * levels + depth): the next vertex of its voxel to place for that depth (global index).
  std::vector<std::uint64_t> cursor_;
  // Per streamline: its lowest and highest voxel index (set by the first range's pass), so that later
  // passes skip the streamlines that have no voxel in their range.
  std::vector<std::array<std::uint32_t, 2>> spans_;
  std::uint64_t order_bytes_ = 0;
  ConversionPlan plan_;  // once the voxel table is built
  // Written block by block: one buffer for the blocks' staging while they are placed, then for the
  // orders' chunks and the vertices read back (fresh pages are dear: a buffer reused is not faulted in
  // again).
  std::unique_ptr<std::uint8_t, void (*)(void*)> pool_{nullptr, std::free};
  VoxlineEnds ends_;  // float32 positions: the voxline ends of the range being built
  std::unique_ptr<VxlStreamWriter> out_;
};

// Part of a batch voxelised on its own thread (stage_part), waiting to be placed in order.
struct StreamingConversion::StagedPart {
  std::uint64_t begin = 0, end = 0;       // streamlines of the batch
  std::uint64_t source_first = 0;         // the index of streamline `begin` in the source
  SinkOf<detail::SharedVoxelIndex> sink;  // every voxline of the part, in order
  std::vector<std::size_t> voxline_ends;  // per streamline: the end of its voxlines in sink.voxlines
  std::vector<std::uint32_t> words;       // packed: the vertices of the voxlines in range, in order
  std::vector<float> xyz;                 // float32: the same
  std::uint64_t bytes() const {
    return sink.bytes() + voxline_ends.capacity() * sizeof(std::size_t) + words.capacity() * sizeof(std::uint32_t) +
           xyz.capacity() * sizeof(float);
  }
};

// What one range's placing pass keeps between batches.
struct StreamingConversion::RangePlacement {
  RangePlacement(const VoxelRange& r, bool first_range, std::span<std::uint8_t> part_of_vert)
      : range(r), tables(first_range), window(part_of_vert) {}
  const VoxelRange& range;
  bool tables;                        // the first range: also the voxline and streamline tables
  std::span<std::uint8_t> window;     // the range's part of VERT
  std::vector<VertexPacker> packers;  // by voxel - range.first (packed positions)
  // Written block by block (plan_.block_staging_bytes > 0): a writer per (local voxel id, level), as cursor_, whose
  // full stagings are written by `queue`'s thread.
  std::unique_ptr<DirectWriteQueue> queue;
  std::vector<std::unique_ptr<DirectRegionWriter>> blocks;
  std::vector<VoxlineEntry> voxline_buffer;
  std::vector<std::uint64_t> streamline_buffer;
  std::uint64_t voxline_index = 0, streamlines = 0;
  StagedPart parts[2][2];  // two sets of two parts: one being staged, one being placed
};

// Part of a batch counted on its own thread in pass 2 (count_part).
struct StreamingConversion::PlanPart {
  Sink sink;
  detail::VoxelUse use;
  detail::VoxelBounds bounds;
  std::uint64_t voxlines = 0, synthetic = 0;  // in the batch being counted
};

void StreamingConversion::fail_changed() const {
  fail_input(path_, std::nullopt,
             "the file changed while it was being converted (--memory-limit reads it several times)");
}

void StreamingConversion::check_source_type() const {
  const SourceMatch match = source_format_of(path_);
  if (!match.format || !match.format->streamable)
    fail_unsupported(path_, "--memory-limit streams TCK sources only (.tck); convert " +
                                std::string(match.format ? match.format->name : "other") + " sources without it");
}

void StreamingConversion::open_stream() {
  reader_ = std::make_unique<BatchReader>(path_, budget_, threads_, settings_.progress);
}

// Pass 1: what plan_voxels' bounds scan finds, and the source's checksum and warnings.
void StreamingConversion::scan() {
  detail::BoundsScan bounds;
  std::uint64_t streamlines = 0, points = 0;
  reader_->each_batch("reading", [&](const Tractogram& b, std::uint64_t first) {
    reader_->note_longest(b, first);
    // In two parts on two threads, merged in order (a scan stops at a bad point; reading goes on for the
    // reader's errors).
    const std::array<std::uint64_t, 3> cut = two_parts(b);
    detail::BoundsScan parts[2];
    parallel_for(2, threads_ > 1 ? 2 : 1, [&](std::uint64_t p, unsigned) {
      parts[p].add(b.positions.data(), b.offsets.data(), cut[p], cut[p + 1], first);
    });
    for (const detail::BoundsScan& part : parts) bounds.merge(part);
    streamlines += b.streamline_count();
    points += b.point_count();
  });
  bounds.check(path_);
  for (int c = 0; c < 3; ++c) {
    lo_[c] = bounds.lo[c];
    hi_[c] = bounds.hi[c];
  }
  longest_step2_ = bounds.longest_step2;
  meta_.streamline_count = streamlines;
  meta_.point_count = points;
  if (settings_.voxel_size_auto) {
    const VoxelSizeChoice choice = choose_voxel_size(points, lo_, hi_, bounds.rms_step(), path_);
    settings_.voxel_size = choice.size;
    voxel_size_choice_ = choice.reason;
  }
  meta_.voxel_size = settings_.voxel_size;
}

// Pass 2: the vertex and segment counts and the tight bounds per voxel (plan_voxels' pass 1), kept per
// voxel only. Each batch is cut in two parts counted on two threads: the first into the source's voxel
// index (sink_, use_, bounds_), the second into a part of its own (PlanPart), merged into it after the
// batch — the counts and bounds do not depend on the order streamlines are counted in.
void StreamingConversion::plan() {
  use_ = detail::VoxelUse(settings_.levels);
  if (meta_.point_count == 0) return;  // no voxels (plan_voxels returns early too)
  grid_ = detail::set_grid(meta_, lo_, hi_, path_);
  // plan_voxels' limit on added points, applied to the whole source (plan_voxels applies it per
  // thread's range: the two can differ only in whether a borderline source is refused).
  synthetic_limit_ =
      static_cast<std::uint64_t>(VoxelizeSettings{}.max_synthetic_per_point * double(meta_.point_count)) + 4096;
  PlanPart main{std::move(sink_), std::move(use_), std::move(bounds_), 0, 0},
      other{Sink(), detail::VoxelUse(settings_.levels), {}, 0, 0};
  PlanPart* parts[2] = {&main, &other};
  std::uint64_t voxlines = 0, synthetic = 0, points = 0;
  reader_->each_batch("voxelising", [&](const Tractogram& b, std::uint64_t first) {
    const std::array<std::uint64_t, 3> cut = two_parts(b);
    // The voxels the limit leaves room for in this batch, half to each part: a part that would need more
    // fails (no matter how many the other adds, so that the outcome does not depend on timing).
    const std::uint64_t room = (plan_held_ + budget_.left()) / voxel_table_bytes_per_voxel(settings_.levels);
    const std::uint64_t start = main.sink.index.coords().size();
    const std::uint64_t headroom = room > start ? room - start : 0;
    const std::uint64_t most[2] = {start + headroom / 2, headroom - headroom / 2};
    parallel_for_first_error_in_order(2, threads_ > 1 ? 2 : 1, [&](std::uint64_t p, unsigned) {
      count_part(b, first, cut[p], cut[p + 1], points, synthetic, most[p], p == 0 ? 0 : start, *parts[p]);
    });
    for (PlanPart* part : parts) {
      voxlines += std::exchange(part->voxlines, 0);
      synthetic += std::exchange(part->synthetic, 0);
    }
    if (synthetic > synthetic_limit_) detail::fail_too_many_synthetic(path_, meta_.voxel_size, longest_step2_);
    // Both parts' tables at their largest (within the limit, by the parts' shares); then the second
    // part's voxels into the first's index.
    const std::vector<detail::Coord>& coords = other.sink.index.coords();
    const std::uint64_t peak = main.sink.index.coords().size() + coords.size();
    const std::uint32_t levels = settings_.levels;
    for (std::uint32_t j = 0; j < coords.size(); ++j) {
      const std::uint32_t i = main.sink.index.find_or_insert(coords[j]);
      main.use.grow_to(main.sink.index.coords().size());
      main.bounds.grow_to(main.sink.index.coords().size());
      for (std::uint32_t d = 0; d < levels; ++d) {
        main.use.vertices[std::size_t(i) * levels + d] += other.use.vertices[std::size_t(j) * levels + d];
        main.use.segments[std::size_t(i) * levels + d] += other.use.segments[std::size_t(j) * levels + d];
      }
      main.bounds.merge(i, other.bounds, j);
    }
    const std::uint64_t sinks = main.sink.bytes() + other.sink.bytes();
    budget_.track(peak * voxel_table_bytes_per_voxel(levels), plan_held_, [] { return std::string(); });
    other = PlanPart{Sink(), detail::VoxelUse(levels), {}, 0, 0};
    budget_.shrink(main.sink.index.coords().size() * voxel_table_bytes_per_voxel(levels), plan_held_);
    budget_.track(sinks, sink_held_, [] { return std::string("the voxline lists of two streamlines"); });
    points += b.point_count();
  });
  sink_ = std::move(main.sink);
  use_ = std::move(main.use);
  bounds_ = std::move(main.bounds);
  meta_.voxline_count = voxlines;
  meta_.synthetic_point_count = synthetic;
}

// On one thread: counts streamlines [begin, end) of batch b (numbered from `first`) into `part`, whose
// index may grow to `most_voxels` (its share of the limit; checked after every streamline, so that a table
// outgrowing the limit is caught before it goes far past it); `other_voxels` are the other part's at the
// batch's start, for the message. `points` and `synthetic` are those of the batches before.
void StreamingConversion::count_part(const Tractogram& b, std::uint64_t first, std::uint64_t begin, std::uint64_t end,
                                     std::uint64_t points, std::uint64_t synthetic, std::uint64_t most_voxels,
                                     std::uint64_t other_voxels, PlanPart& part) const {
  const float* pts = b.positions.data();
  const std::uint64_t bytes_per_voxel = voxel_table_bytes_per_voxel(settings_.levels);
  for (std::uint64_t k = begin; k < end; ++k) {
    part.sink.voxlines.clear();
    part.sink.synthetic_xyz.clear();
    detail::voxelize_streamline(grid_, pts, b.offsets[k], b.offsets[k + 1] - b.offsets[k], part.sink,
                                synthetic_limit_ - std::min(synthetic_limit_, synthetic + part.synthetic));
    if (part.sink.too_many_synthetic) detail::fail_too_many_synthetic(path_, meta_.voxel_size, longest_step2_);
    part.synthetic += part.sink.synthetic_xyz.size() / 3;
    const std::size_t n_local = part.sink.index.coords().size();
    part.use.grow_to(n_local);
    detail::count_voxel_use(part.sink.voxlines, streamline_depth(first + k, settings_.levels), part.use, path_);
    part.bounds.grow_to(n_local);
    for (std::size_t j = 0; j < part.sink.voxlines.size(); ++j)
      part.bounds.add_voxline(part.sink.voxlines, j, pts, part.sink.synthetic_xyz.data());
    part.voxlines += part.sink.voxlines.size();
    if (n_local > most_voxels) {
      const std::uint64_t voxels = n_local + other_voxels;
      // Voxels turn up ever more slowly: extrapolating from the points read so far overestimates.
      const std::uint64_t read = points + b.offsets[k + 1];
      const std::uint64_t all = static_cast<std::uint64_t>(double(voxels) * double(meta_.point_count) / double(read));
      budget_.fail(all * bytes_per_voxel, budget_.used() - plan_held_,
                   "the voxel table (" + std::to_string(voxels) + " voxels after " + std::to_string(read) + " of " +
                       std::to_string(meta_.point_count) + " points; about " + std::to_string(all) +
                       " in all, extrapolated)",
                   ", or a larger --voxel-size");
    }
  }
}

// The voxel table sorted by (z, y, x), as plan_voxels and layout_orders make it.
void StreamingConversion::build_table() {
  detail::LocalVoxels table{&sink_.index.coords(), &use_, {}, {}};
  use_.grow_to(sink_.index.coords().size());
  detail::VoxelTable built = detail::build_voxel_table({&table, 1}, settings_.levels, meta_, path_);
  voxels_ = std::move(built.voxels);
  levels_ = std::move(built.levels);
  use_ = detail::VoxelUse(settings_.levels);
  global_id_ = std::move(table.global_id);
  cursor_ = std::move(table.cursor);
  for (std::uint32_t local = 0; local < global_id_.size(); ++local)
    bounds_.set_tight_bounds(local, voxels_[global_id_[local]]);
  bounds_ = detail::VoxelBounds();
  meta_.stored_order_count = static_cast<std::uint32_t>(order_set_.directions.size());
  meta_.order_set = static_cast<std::uint32_t>(order_set_.kind);
  meta_.position_encoding = static_cast<std::uint32_t>(settings_.positions);
  order_bytes_ = layout_orders(voxels_, levels_, settings_.levels, meta_.stored_order_count);
}

// Pass 2 + k: the blocks and orders of one range.
void StreamingConversion::build_range(const VoxelRange& r, std::size_t index, std::size_t count) {
  const std::string of = " " + std::to_string(index + 1) + "/" + std::to_string(count);
  const bool tables = index == 0;
  const std::uint64_t range_vertices = r.vertex_end - r.vertex_first;
  if (plan_.block_staging_bytes > 0) {  // VERT written block by block, then read back for the orders
    place_range(r, tables, of, {});
    write_orders(r, {}, "ordering" + of);
    return;
  }
  // The range's vertices are placed straight into the output (a mapping of its part of VERT); the
  // orders are built from them there before it is unmapped.
  out_->append_in_place(
      VxlStreamWriter::kVert, range_vertices * vertex_bytes(settings_.positions), threads_,
      [&](std::span<std::uint8_t> window) { place_range(r, tables, of, window); },
      [&](std::span<const std::uint8_t> window) { write_orders(r, window, "ordering" + of); });
}

// Pass 2 + k, reading: places range r's vertices in `window` (its part of VERT); the first range also
// writes the voxline and streamline tables. Each batch is cut in two parts that are voxelised and packed
// on their own threads (stage_part: packing needs only the voxel, whose tight bounds came from pass 2),
// then placed in streamline order (place_part), which is what fixes where each vertex goes.
void StreamingConversion::place_range(const VoxelRange& r, bool tables, const std::string& of,
                                      std::span<std::uint8_t> window) {
  auto t0 = Clock::now();
  RangePlacement placing(r, tables, window);
  if (plan_.block_staging_bytes > 0) open_block_writers(placing);
  if (packed()) {
    placing.packers.reserve(r.end - r.first);
    for (std::size_t g = r.first; g < r.end; ++g) placing.packers.emplace_back(voxels_[g]);
  } else {
    ends_ = VoxlineEnds(r.vertex_end - r.vertex_first);
  }
  if (tables) {
    placing.voxline_buffer.reserve(kTableBufferEntries);
    placing.streamline_buffer.reserve(kTableBufferEntries);
  }
  // Batch k is staged in two parts on two threads while batch k - 1, staged before, is placed on a third:
  // placing (in streamline order) is the serial part of the pass.
  int staging = 0;           // the set of parts the current batch is staged in
  bool other_placed = true;  // whether the other set's parts are placed
  auto place_staged = [&](int set) {
    for (const StagedPart& part : placing.parts[set]) place_part(placing, part);
  };
  reader_->each_batch("placing" + of, [&](const Tractogram& b, std::uint64_t first) {
    if (first + b.streamline_count() > spans_.size()) fail_changed();  // more streamlines than pass 1 saw
    const std::array<std::uint64_t, 3> cut = two_parts(b);
    // Item 0 places the earlier batch, so that its errors come first.
    parallel_for_first_error_in_order(3, threads_ > 1 ? 3 : 1, [&](std::uint64_t item, unsigned) {
      if (item == 0) {
        if (!other_placed) place_staged(1 - staging);
        return;
      }
      stage_part(placing, b, first, cut[item - 1], cut[item], placing.parts[staging][item - 1]);
    });
    other_placed = false;
    staging = 1 - staging;
    std::uint64_t staged = 0;
    for (const auto& set : placing.parts)
      for (const StagedPart& part : set) staged += part.bytes();
    budget_.track(staged, staged_held_, [] { return std::string("the voxlines of two batches being placed"); });
  });
  if (!other_placed) place_staged(1 - staging);
  if (placing.queue) placing.queue->finish();  // rethrows a failed write
  placing.blocks.clear();  // each wrote its last bytes with its last append (checked below: all complete)
  if (placing.streamlines != meta_.streamline_count || (tables && placing.voxline_index != meta_.voxline_count))
    fail_changed();
  const std::uint32_t levels = settings_.levels;
  for (std::size_t local = 0; local < global_id_.size(); ++local) {
    const std::uint32_t g = global_id_[local];
    if (g < r.first || g >= r.end) continue;
    for (std::uint32_t d = 0; d < levels; ++d)
      if (cursor_[local * levels + d] !=
          voxels_[g].vertex_first + depth_end_vertex(voxels_[g], level_row(levels_, g, levels), d))
        fail_changed();
  }
  if (tables) {
    placing.streamline_buffer.push_back(placing.voxline_index);
    out_->append_items<std::uint64_t>(VxlStreamWriter::kStrm, placing.streamline_buffer);
    out_->append_items<VoxlineEntry>(VxlStreamWriter::kVxln, placing.voxline_buffer);
  }
  summary_.voxelize_seconds += seconds_since(t0);
}

// A writer per (voxel, level) block of range r with vertices, from the block's first vertex (cursor_,
// before any is placed) to its end.
void StreamingConversion::open_block_writers(RangePlacement& placing) const {
  const VoxelRange& r = placing.range;
  const std::uint32_t levels = settings_.levels;
  const std::uint64_t bytes = vertex_bytes(settings_.positions);
  placing.blocks.resize(cursor_.size());
  std::uint8_t* staging = pool_.get();  // the queue's spares, then each block's staging, one after another
  std::vector<std::uint8_t*> spares;
  for (std::uint64_t k = 0; k < kSpareBlockStagings; ++k, staging += plan_.block_staging_bytes)
    spares.push_back(staging);
  placing.queue = out_->write_queue(std::move(spares), plan_.block_staging_bytes);
  for (std::size_t local = 0; local < global_id_.size(); ++local) {
    const std::uint32_t g = global_id_[local];
    if (g < r.first || g >= r.end) continue;
    for (std::uint32_t d = 0; d < levels; ++d) {
      const std::uint64_t first = cursor_[local * levels + d];
      const std::uint64_t end =
          voxels_[g].vertex_first + depth_end_vertex(voxels_[g], level_row(levels_, g, levels), d);
      if (end > first) {
        const std::uint64_t size = DirectRegionWriter::staging_size((end - first) * bytes, plan_.block_staging_bytes);
        if (std::uint64_t(staging - pool_.get()) + size > plan_.pool_bytes)
          throw std::logic_error("StreamingConversion: the blocks' staging outgrows its pool");
        placing.blocks[local * levels + d] =
            out_->region_writer(VxlStreamWriter::kVert, first * bytes, (end - first) * bytes, plan_.block_staging_bytes,
                                staging, placing.queue.get());
        staging += size;
      }
    }
  }
}

// On one thread: voxelises streamlines [begin, end) of batch b (numbered from `first` in the source) and
// stages the vertices of their voxlines in range, packed (or as float32), in streamline order.
void StreamingConversion::stage_part(const RangePlacement& placing, const Tractogram& b, std::uint64_t first,
                                     std::uint64_t begin, std::uint64_t end, StagedPart& part) const {
  const VoxelRange& r = placing.range;
  part.begin = begin;
  part.end = end;
  part.source_first = first + begin;
  part.sink.index.index = &sink_.index;
  part.sink.voxlines.clear();
  part.sink.synthetic_xyz.clear();
  part.voxline_ends.clear();
  part.words.clear();
  part.xyz.clear();
  const float* pts = b.positions.data();
  std::vector<float> voxline_xyz;  // one voxline's vertices on their way to being packed
  part.sink.too_many_synthetic = false;
  for (std::uint64_t k = begin; k < end; ++k) {
    const std::size_t start = part.sink.voxlines.size();
    if (!placing.tables) {
      const std::array<std::uint32_t, 2>& span = spans_[first + k];
      if (span[1] < r.first || span[0] >= r.end) {  // no voxel in this range (or none at all)
        part.voxline_ends.push_back(start);
        continue;
      }
    }
    detail::voxelize_streamline(grid_, pts, b.offsets[k], b.offsets[k + 1] - b.offsets[k], part.sink, synthetic_limit_);
    if (part.sink.too_many_synthetic) fail_changed();
    part.voxline_ends.push_back(part.sink.voxlines.size());
    const std::span<const TempVoxline> streamline(part.sink.voxlines.data() + start, part.sink.voxlines.size() - start);
    for (std::size_t j = 0; j < streamline.size(); ++j) {
      const TempVoxline& v = streamline[j];
      if (v.voxel >= global_id_.size()) fail_changed();  // a voxel pass 2 did not see
      const std::uint32_t g = global_id_[v.voxel];
      if (g < r.first || g >= r.end) continue;
      const std::uint64_t used = v.own() + (j + 1 < streamline.size() ? 1 : 0);
      if (!packed()) {
        const std::size_t at = part.xyz.size();
        part.xyz.resize(at + 3 * used);
        detail::place_voxline(streamline, j, pts, part.sink.synthetic_xyz.data(), part.xyz.data() + at);
        continue;
      }
      voxline_xyz.resize(3 * used);
      detail::place_voxline(streamline, j, pts, part.sink.synthetic_xyz.data(), voxline_xyz.data());
      // A vertex outside the bounds pass 2 found would be clamped: the source changed.
      const VoxelEntry& voxel = voxels_[g];
      for (std::uint64_t e = 0; e < used; ++e)
        for (int c = 0; c < 3; ++c)
          if (!(voxline_xyz[3 * e + c] >= voxel.tight_min[c] && voxline_xyz[3 * e + c] <= voxel.tight_max[c]))
            fail_changed();
      const std::size_t at = part.words.size();
      part.words.resize(at + used);
      placing.packers[g - r.first].words(voxline_xyz.data(), used, part.words.data() + at);
      part.words[at + used - 1] |= kPackedVoxlineEnd;
    }
  }
}

// In streamline order: copies a staged part's vertices to their blocks (each voxel's next place for the
// streamline's depth) and, for the first range, writes its voxline and streamline table entries.
void StreamingConversion::place_part(RangePlacement& placing, const StagedPart& part) {
  const std::uint64_t first = part.source_first;
  const VoxelRange& r = placing.range;
  const std::uint32_t levels = settings_.levels;
  auto* const words = reinterpret_cast<std::uint32_t*>(placing.window.data());
  auto* const vertices = reinterpret_cast<float*>(placing.window.data());
  std::uint64_t staged = 0;  // vertices of the part placed so far
  std::size_t start = 0;
  for (std::uint64_t k = 0; k < part.end - part.begin; ++k) {
    const std::size_t end = part.voxline_ends[k];
    const std::span<const TempVoxline> streamline(part.sink.voxlines.data() + start, end - start);
    start = end;
    std::array<std::uint32_t, 2>& span = spans_[first + k];
    if (placing.tables) {
      span = {std::numeric_limits<std::uint32_t>::max(), 0};
      placing.streamline_buffer.push_back(placing.voxline_index);
      if (placing.streamline_buffer.size() == kTableBufferEntries) {
        out_->append_items<std::uint64_t>(VxlStreamWriter::kStrm, placing.streamline_buffer);
        placing.streamline_buffer.clear();
      }
    } else if (span[1] < r.first || span[0] >= r.end) {
      continue;
    }
    const std::uint32_t depth = streamline_depth(first + k, levels);
    for (std::size_t j = 0; j < streamline.size(); ++j) {
      const TempVoxline& v = streamline[j];
      const std::uint32_t g = global_id_[v.voxel];  // checked by stage_part
      const std::uint32_t own = v.own();
      if (placing.tables) {
        span = {std::min(span[0], g), std::max(span[1], g)};
        placing.voxline_buffer.push_back({g, own | (v.synthetic != kNoSynthetic ? kVoxlineSyntheticFirst : 0u)});
        if (placing.voxline_buffer.size() == kTableBufferEntries) {
          out_->append_items<VoxlineEntry>(VxlStreamWriter::kVxln, placing.voxline_buffer);
          placing.voxline_buffer.clear();
        }
      }
      if (g < r.first || g >= r.end) continue;
      const std::uint64_t used = own + (j + 1 < streamline.size() ? 1 : 0);
      std::uint64_t& cursor = cursor_[std::size_t(v.voxel) * levels + depth];
      const std::uint64_t block_end =
          voxels_[g].vertex_first + depth_end_vertex(voxels_[g], level_row(levels_, g, levels), depth);
      if (cursor > block_end || used > block_end - cursor) fail_changed();
      const std::uint64_t at = cursor - r.vertex_first;
      if (!packed()) ends_.set(at + used - 1);
      if (!placing.blocks.empty()) {
        const auto* from = packed() ? reinterpret_cast<const std::uint8_t*>(part.words.data() + staged)
                                    : reinterpret_cast<const std::uint8_t*>(part.xyz.data() + 3 * staged);
        placing.blocks[std::size_t(v.voxel) * levels + depth]->append({from, used * vertex_bytes(settings_.positions)});
      } else if (packed()) {
        std::copy_n(part.words.data() + staged, used, words + at);
      } else {
        std::copy_n(part.xyz.data() + 3 * staged, 3 * used, vertices + 3 * at);
      }
      staged += used;
      cursor += used;
    }
    placing.voxline_index += streamline.size();
  }
  placing.streamlines += part.end - part.begin;
}

// The orders of range r's voxels, a chunk of consecutive voxels at a time (each chunk's voxels spread
// over the range's ordering threads), built in place in ORDR. The vertices are range r's part of VERT in
// memory (`range_vertices`), or, when VERT was written block by block, read back a chunk at a time: the
// next chunk's on another thread while this one is built.
void StreamingConversion::write_orders(const VoxelRange& r, std::span<const std::uint8_t> range_vertices,
                                       const std::string& stage) {
  // Per ordering thread, sized for the range's largest voxel once (fresh pages are dear; see above).
  std::vector<std::optional<VoxelOrderWriter>> writers(r.order_threads);
  std::vector<VoxlineEnds> block_ends(r.order_threads);
  std::vector<std::size_t> cuts{r.first};  // chunk c: voxels [cuts[c], cuts[c + 1])
  while (cuts.back() < r.end) {
    const std::size_t first = cuts.back();
    std::size_t end = first + 1;
    while (end < r.end && orders_start(end + 1) - orders_start(first) <= plan_.order_chunk_bytes) ++end;
    cuts.push_back(end);
  }
  auto vertex_start = [&](std::size_t i) { return i < r.end ? voxels_[i].vertex_first : r.vertex_end; };
  const std::uint64_t vertex_size = vertex_bytes(settings_.positions);
  // The chunks' orders and the vertices read back: in pool_ after the blocks' staging is done with.
  std::unique_ptr<std::uint8_t[]> own_chunks[2];
  std::uint8_t* chunks[2] = {};
  std::span<std::uint8_t> read_buffers[2];
  if (plan_.block_staging_bytes > 0) {
    for (int b = 0; b < 2; ++b) {
      chunks[b] = pool_.get() + b * plan_.pool_chunk_bytes;
      read_buffers[b] = {pool_.get() + 2 * plan_.pool_chunk_bytes + b * plan_.pool_read_back_bytes,
                         plan_.pool_read_back_bytes};
    }
  }
  // Chunk c's vertices: in memory, or read back (on another thread, while the chunk before is built).
  auto vertices_of = [&](std::size_t c) {
    const std::uint64_t from = vertex_start(cuts[c]), to = vertex_start(cuts[c + 1]);
    if (plan_.block_staging_bytes == 0)
      return range_vertices.subspan((from - r.vertex_first) * vertex_size, (to - from) * vertex_size);
    return out_->read_back(VxlStreamWriter::kVert, (to - from) * vertex_size, read_buffers[c % 2]);
  };
  auto fetch = [&](std::size_t c) {
    return BackgroundTask<std::span<const std::uint8_t>>([&, c] { return vertices_of(c); });
  };
  const bool read_back = plan_.block_staging_bytes > 0;
  // With direct writes a chunk is written on its own thread while the next one is built (the write waits
  // on the disk, not the CPU); through the page cache it is written before the next one is built.
  // The buffers are taken once at the largest chunk's size and not cleared: the writers write every
  // byte of their voxels' orders, padding included. (Regrowing and zeroing them per chunk took 3 of the
  // 11 s of a 10M conversion's orders: fresh pages cost much on a virtual machine.)
  std::vector<std::size_t> by_size;  // a chunk's voxels
  BackgroundTask<std::span<const std::uint8_t>> next_vertices;
  if (read_back && cuts.size() > 1) next_vertices = fetch(0);
  BackgroundTask<> writing;
  for (std::size_t c = 0; c + 1 < cuts.size(); ++c) {
    auto t0 = Clock::now();
    const std::size_t first = cuts[c], end = cuts[c + 1];
    const std::span<const std::uint8_t> vertices = read_back ? next_vertices.get() : vertices_of(c);
    if (read_back && c + 2 < cuts.size()) next_vertices = fetch(c + 1);
    const std::uint64_t base = orders_start(first);
    const int b = plan_.direct_staging_bytes > 0 ? c % 2 : 0;
    if (chunks[b] == nullptr) {
      own_chunks[b] = std::make_unique_for_overwrite<std::uint8_t[]>(plan_.order_chunk_bytes);
      chunks[b] = own_chunks[b].get();
    }
    const std::span<std::uint8_t> chunk(chunks[b], orders_start(end) - base);
    // Largest voxels first, so that the threads finish the chunk at about the same time.
    by_size.resize(end - first);
    std::iota(by_size.begin(), by_size.end(), first);
    std::stable_sort(by_size.begin(), by_size.end(),
                     [&](std::size_t a, std::size_t b) { return voxels_[a].vertex_count > voxels_[b].vertex_count; });
    parallel_for(end - first, r.order_threads, [&](std::uint64_t i, unsigned t) {
      if (!writers[t]) writers[t].emplace(order_set_, r.max_vertices);
      const std::size_t g = by_size[i];
      write_voxel_orders(r, g, vertices, vertex_start(first), *writers[t], block_ends[t],
                         chunk.data() + (voxels_[g].order_offset - base));
    });
    if (writing.valid()) writing.get();  // rethrows a failed write
    if (plan_.direct_staging_bytes > 0)
      writing = BackgroundTask<>([this, chunk] { out_->append(VxlStreamWriter::kOrdr, chunk); });
    else
      out_->append(VxlStreamWriter::kOrdr, chunk);
    summary_.orders_seconds += seconds_since(t0);
    report(stage, double(end - r.first) / double(std::max<std::size_t>(1, r.end - r.first)));
  }
  if (writing.valid()) writing.get();
}

// Voxel g's orders at `dst`, from its block in `vertices` (the part of VERT from vertex
// `vertices_first`): the orders sort the positions the file holds. A float32 block's voxline ends are
// copied into `block_ends` (a packed block holds its own).
void StreamingConversion::write_voxel_orders(const VoxelRange& r, std::size_t g, std::span<const std::uint8_t> vertices,
                                             std::uint64_t vertices_first, VoxelOrderWriter& writer,
                                             VoxlineEnds& block_ends, std::uint8_t* dst) {
  VoxelEntry v = voxels_[g];
  const std::span<const LevelEntry> row = level_row(levels_, g, settings_.levels);
  const std::uint64_t at = v.vertex_first - vertices_first;
  v.vertex_first = 0;
  if (!packed()) {
    block_ends.reset(v.vertex_count);
    const std::uint64_t in_range = voxels_[g].vertex_first - r.vertex_first;  // ends_ counts from the range
    for (std::uint32_t e = 0; e < v.vertex_count; ++e)
      if (ends_.test(in_range + e)) block_ends.set(e);
    const float* xyz = reinterpret_cast<const float*>(vertices.data()) + 3 * at;
    writer.write(v, row, {xyz, 3 * std::size_t(v.vertex_count)}, block_ends, dst);
    return;
  }
  writer.write_packed(v, row, reinterpret_cast<const std::uint32_t*>(vertices.data()) + at, dst);
}

void StreamingConversion::write_rest() {
  out_->append_meta(meta_);
  std::vector<DirectionEntry> directions = order_directions(order_set_);
  out_->append_items<DirectionEntry>(VxlStreamWriter::kDirs, directions);
  if (order_set_.per_voxel()) {  // VDIR, a function of (seed, voxel coordinate): made in bounded slices
    const std::size_t slice = 4096;
    std::vector<DirectionEntry> voxel_directions;
    for (std::size_t first = 0; first < voxels_.size(); first += slice) {
      const std::span<const VoxelEntry> part =
          std::span<const VoxelEntry>(voxels_).subspan(first, std::min(slice, voxels_.size() - first));
      voxel_directions.resize(part.size() * directions.size());
      fill_voxel_directions(order_set_, part, voxel_directions);
      out_->append_items<DirectionEntry>(VxlStreamWriter::kVdir, voxel_directions);
    }
  }
  out_->append_items<VoxelEntry>(VxlStreamWriter::kVoxt, voxels_);
  if (!levels_.empty()) out_->append_items<LevelEntry>(VxlStreamWriter::kLods, levels_);
}

ConvertSummary StreamingConversion::run() {
  if (settings_.memory_limit == 0) throw std::logic_error("convert_streaming: memory_limit must be > 0");
  check_source_type();
  order_set_ = parse_order_set(settings_.orders);
  threads_ = resolve_threads(settings_.threads);
  if (!settings_.voxel_size_auto) detail::check_voxel_size(settings_.voxel_size, path_);
  detail::check_level_count(settings_.levels, path_);
  summary_.passes = 0;

  auto t0 = Clock::now();
  open_stream();
  scan();
  summary_.read_seconds = seconds_since(t0);

  t0 = Clock::now();
  plan();
  build_table();
  summary_.voxelize_seconds = seconds_since(t0);
  plan_ = plan_conversion(budget_, {meta_, voxels_, levels_, settings_.levels, settings_.positions, order_bytes_,
                                    threads_, reader_->plan().batch_streamlines, tuning_.order_chunk_bytes});
  staged_held_ = plan_.staged_bytes;
  spans_.resize(meta_.streamline_count);
  if (plan_.block_staging_bytes > 0) {
    void* p = std::aligned_alloc(DirectRegionWriter::kBlock, plan_.pool_bytes);
    if (p == nullptr) throw std::bad_alloc();
    pool_.reset(static_cast<std::uint8_t*>(p));
  }
  const std::vector<VoxelRange>& ranges = plan_.ranges;

  const std::string provenance = provenance_json(reader_->source(), settings_, threads_, voxel_size_choice_);
  out_ = std::make_unique<VxlStreamWriter>(out_path_, section_sizes(meta_, order_bytes_, provenance.size(), 0),
                                           plan_.direct_staging_bytes);
  for (std::size_t k = 0; k < ranges.size(); ++k) {
    build_range(ranges[k], k, ranges.size());
#if defined(__GLIBC__)
    malloc_trim(0);  // give back what the range freed, lest the allocator keep it resident for the next one
#endif
  }

  report("writing", 0.0);
  t0 = Clock::now();
  write_rest();
  out_->append(VxlStreamWriter::kProv, {reinterpret_cast<const std::uint8_t*>(provenance.data()), provenance.size()});
  out_->commit();
  summary_.write_seconds += seconds_since(t0);
  report("writing", 1.0);

  summary_.take_counts(meta_);
  summary_.passes = reader_->passes();
  summary_.partitions = ranges.size();
  summary_.vertices_read_back = plan_.block_staging_bytes > 0;
  for (const VoxelRange& r : ranges) summary_.partition_starts.push_back(r.first);
  summary_.warnings = reader_->source().warnings;
  return summary_;
}

}  // namespace

ConvertSummary convert_streaming(const std::string& source_path, const std::string& out_path,
                                 const ConvertSettings& settings) {
  return convert_streaming(source_path, out_path, settings, StreamingTuning{});
}

ConvertSummary convert_streaming(const std::string& source_path, const std::string& out_path,
                                 const ConvertSettings& settings, const StreamingTuning& tuning) {
  StreamingConversion conversion(source_path, out_path, settings, tuning);
  return conversion.run();
}

}  // namespace vxl
