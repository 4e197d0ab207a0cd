#include "converter/streaming_convert.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <future>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <span>
#include <utility>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "converter/readers/source_formats.h"
#include "converter/readers/tck_stream.h"
#include "converter/segment_orders.h"
#include "converter/voxel_size_auto.h"
#include "converter/voxel_table.h"
#include "converter/voxelize.h"
#include "format/base/error.h"
#include "format/base/memory_size.h"
#include "format/base/parallel.h"
#include "format/vxl_positions.h"
#include "format/vxl_stream_writer.h"

namespace vxl {
namespace {

using detail::Grid;
using detail::kNoSynthetic;
using detail::TempVoxline;
using detail::VoxelIndex;
using Clock = std::chrono::steady_clock;

constexpr std::uint64_t kMiB = 1ull << 20;
// The program itself before any work: code, libraries, thread stacks, allocator slack (voxlines
// measures about 7 MiB of resident memory at start; the rest is margin).
constexpr std::uint64_t kBaselineBytes = 16 * kMiB;
// The voxel table while it is built and used, at its peak (build_table): hash index (coordinates and
// slots, with their growth: up to 40 bytes), counts per voxel (with growth: 32), tight bounds (with
// growth: 48), sort order, global id, the table itself (64) and cursor (8) — 200 bytes, and a margin.
constexpr std::uint64_t kPlanBytesPerVoxel = 240;
// Each level of detail past the first adds counts per depth (32 with growth), a cursor (8), a LODS entry
// (8) and the counts summed per voxel while the table is built (16).
constexpr std::uint64_t plan_bytes_per_voxel(std::uint32_t levels) { return kPlanBytesPerVoxel + 64 * (levels - 1); }
// Memory per point of a batch being read, at worst: two batches (one read while the other is processed),
// each of whose positions may have twice the capacity in use.
constexpr std::uint64_t kHeldBytesPerPoint = 2 * 2 * 3 * sizeof(float);
// The output is written past the page cache (DirectRegionWriter: far cheaper on a virtual machine) under
// limits of at least this much, staged this much per section.
constexpr std::uint64_t kDirectWritesFromLimit = 256 * kMiB;
constexpr std::uint64_t kDirectStagingBytes = 2 * kMiB;
// With direct writes VERT is not held in memory when its blocks are few enough: each (voxel, level)
// block is written through a staging of its own of this size (less where an eighth of the memory left
// does not allow, but never under the minimum), then read back a chunk of voxels at a time for their
// orders. Why: VERT is the conversion's largest buffer (2.3 GB for 10M streamlines), and on a virtual
// machine whose host takes back the guest's free memory every fresh page costs about as much as
// writing and reading it back past the page cache (measured: 2.7 s per GiB faulted in, against 2.9 GB/s
// direct writes and 1.4-3 GB/s direct reads).
constexpr std::uint64_t kBlockStagingBytes = 128 * 1024;
constexpr std::uint64_t kMinBlockStagingBytes = 16 * 1024;
// Spare stagings for the blocks' write queue (DirectWriteQueue): how far the writes may fall behind.
constexpr std::uint64_t kSpareBlockStagings = 32;
// Voxline and streamline table entries written at once.
constexpr std::size_t kTableBufferEntries = 1 << 16;
// The orders are built a run of voxels at a time, in a buffer of at most this size and an
// eighth of the memory left (or of the largest voxel's orders, if more): large enough that each run keeps every
// ordering thread busy.
constexpr std::uint64_t kOrderChunkBytes = 256 * kMiB;

// Where a batch is cut into two parts of about as many points each, for two threads: streamlines
// [cut[0], cut[1]) and [cut[1], cut[2]).
std::array<std::uint64_t, 3> two_parts(const Tractogram& b) {
  const std::uint64_t n = b.streamline_count();
  const std::uint64_t half =
      std::upper_bound(b.offsets.begin(), b.offsets.end(), b.point_count() / 2) - b.offsets.begin() - 1;
  return {0, std::min(half, n), n};
}

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The memory the conversion holds, held against the limit.
class Budget {
 public:
  Budget(std::uint64_t limit, std::string path) : limit_(limit), path_(std::move(path)) {}
  std::uint64_t used() const { return used_; }
  std::uint64_t left() const { return used_ < limit_ ? limit_ - used_ : 0; }
  // Takes `bytes` more, or throws Unsupported naming `what` (a singular noun phrase), what it needs and a
  // limit that would do.
  void take(std::uint64_t bytes, const std::string& what, const std::string& hint = "") {
    if (bytes > left()) fail(bytes, used_, what, hint);
    used_ += bytes;
  }
  // Follows a buffer that grows to `bytes`: takes its growth since `held`, which it updates. what() names it.
  template <typename What>
  void track(std::uint64_t bytes, std::uint64_t& held, What&& what, const std::string& hint = "") {
    if (bytes <= held) return;
    if (bytes - held > left()) fail(bytes, used_ - held, what(), hint);
    used_ += bytes - held;
    held = bytes;
  }
  // Gives back what a buffer followed by track() no longer holds once it is down to `bytes`.
  void shrink(std::uint64_t bytes, std::uint64_t& held) {
    if (bytes >= held) return;
    used_ -= held - bytes;
    held = bytes;
  }
  [[noreturn]] void fail(std::uint64_t needs, std::uint64_t others, const std::string& what,
                         const std::string& hint = "") const {
    // A quarter more than the sum, for what comes later.
    throw Error(ErrorKind::Unsupported, path_, std::nullopt,
                "--memory-limit " + format_memory_size(limit_) + " is too small: " + what + " needs " +
                    format_memory_size(needs) +
                    (others > 0 ? " on top of " + format_memory_size(others) + " already taken" : std::string()) +
                    "; use --memory-limit " + memory_limit_argument((needs + others) / 4 * 5) + " or more" + hint);
  }

 private:
  std::uint64_t limit_;
  std::uint64_t used_ = 0;
  std::string path_;
};

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

// A range of the voxel table, built in one pass.
struct Range {
  std::size_t first = 0, end = 0;  // voxels
  std::uint64_t vertex_first = 0, vertex_end = 0;
  std::uint32_t max_vertices = 0;
  unsigned order_threads = 1;  // set by cut_ranges
};

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
  std::vector<Range> cut_ranges();
  void build_range(const Range& r, std::size_t index, std::size_t count);
  struct PlanPart;
  void count_part(const Tractogram& b, std::uint64_t first, std::uint64_t begin, std::uint64_t end,
                  std::uint64_t points, std::uint64_t synthetic, std::uint64_t most_voxels, std::uint64_t other_voxels,
                  PlanPart& part) const;
  struct StagedPart;
  struct RangePlacement;
  void place_range(const Range& r, bool tables, const std::string& of, std::span<std::uint8_t> window);
  void open_block_writers(RangePlacement& placing) const;
  void stage_part(const RangePlacement& placing, const Tractogram& b, std::uint64_t first, std::uint64_t begin,
                  std::uint64_t end, StagedPart& part) const;
  void place_part(RangePlacement& placing, const StagedPart& part);
  void write_orders(const Range& r, std::span<const std::uint8_t> range_vertices, const std::string& stage);
  void write_voxel_orders(const Range& r, std::size_t g, std::span<const std::uint8_t> vertices,
                          std::uint64_t vertices_first, VoxelOrderWriter& writer, VoxlineEnds& block_ends,
                          std::uint8_t* dst);
  // The memory VERT's stagings take when written block by block: the write queue's spares and each
  // (voxel, level) block's own (DirectRegionWriter::staging_size), as open_block_writers carves them.
  std::uint64_t block_staging_total(std::uint64_t staging) const;
  // The most VERT bytes of any run of consecutive voxels whose orders fit in a chunk (read back at once).
  std::uint64_t largest_chunk_vertex_bytes() const;
  bool packed() const { return settings_.positions == PositionEncoding::Packed; }
  // Where voxel i's orders start in ORDR (i = voxel count: the payload's end).
  std::uint64_t orders_start(std::size_t i) const {
    return i < voxels_.size() ? voxels_[i].order_offset : order_bytes_;
  }
  // Memory per ordering thread besides its sort buffers: a float32 block's end bits.
  std::uint64_t end_bits_bytes(std::uint32_t max_vertices) const { return packed() ? 0 : (max_vertices / 64 + 1) * 8; }
  void write_rest();
  [[noreturn]] void fail_changed() const;
  // Reads the source once, calling body(batch, index of its first streamline) per batch.
  template <typename Body>
  void each_batch(const std::string& stage, Body&& body);
  void report(const std::string& stage, double fraction) const {
    if (settings_.progress) settings_.progress(stage.c_str(), fraction);
  }

  std::string path_, out_path_;
  ConvertSettings settings_;
  StreamingTuning tuning_;
  std::string voxel_size_choice_;  // --voxel-size auto's reason, once scan() has chosen
  Budget budget_;
  OrderSetSpec order_set_;
  unsigned threads_ = 1;
  ConvertSummary summary_;

  std::unique_ptr<TckStream> stream_;
  Tractogram batches_[2];  // one processed while the next is read
  std::uint64_t batch_items_ = 0, batch_held_ = 0, max_points_held_ = 0;
  std::uint64_t longest_ = 0, longest_index_ = 0;  // the longest streamline seen (in points)

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
  std::uint64_t order_chunk_bytes_ = 0;
  std::uint64_t direct_staging_ = 0;  // 0: the output is written through the page cache
  std::uint64_t block_staging_ = 0;   // > 0: VERT is written block by block and read back, not held
  // Written block by block: one buffer for the blocks' staging while they are placed, then for the
  // orders' chunks and the vertices read back (fresh pages are dear: a buffer reused is not faulted in
  // again).
  std::unique_ptr<std::uint8_t, void (*)(void*)> pool_{nullptr, std::free};
  std::uint64_t pool_bytes_ = 0, pool_chunk_bytes_ = 0, pool_read_back_bytes_ = 0;  // the orders' parts of pool_
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
  RangePlacement(const Range& r, bool first_range, std::span<std::uint8_t> part_of_vert)
      : range(r), tables(first_range), window(part_of_vert) {}
  const Range& range;
  bool tables;                        // the first range: also the voxline and streamline tables
  std::span<std::uint8_t> window;     // the range's part of VERT
  std::vector<VertexPacker> packers;  // by voxel - range.first (packed positions)
  // Written block by block (block_staging_ > 0): a writer per (local voxel id, level), as cursor_, whose
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

template <typename Body>
void StreamingConversion::each_batch(const std::string& stage, Body&& body) {
  stream_->rewind();
  ++summary_.passes;
  report(stage, 0.0);
  const double size = double(std::max<std::uint64_t>(1, stream_->file_size()));
  const bool read_ahead = threads_ > 1;
  std::uint64_t first = 0;
  auto read = [&](int b) { return stream_->next(batches_[b], batch_items_, max_points_held_); };
  auto check_overflow = [&](const Tractogram& b) {
    if (stream_->overflowed())
      budget_.fail(b.point_count() * kHeldBytesPerPoint, budget_.used() - batch_held_,
                   "streamline " + std::to_string(first + b.streamline_count()) + ", of more than " +
                       std::to_string(b.point_count() - b.offsets.back()) + " points, held whole while reading,");
  };
  int current = 0;
  bool more = read(current);
  check_overflow(batches_[current]);
  while (more) {
    const int other = 1 - current;
    parallel_invoke(
        read_ahead, [&] { body(static_cast<const Tractogram&>(batches_[current]), first); },
        [&] { more = read(other); });
    first += batches_[current].streamline_count();
    current = other;
    check_overflow(batches_[current]);
    // Both batches keep their largest size; pass 1 finds it (later passes cut the same batches).
    const std::uint64_t bytes =
        (batches_[0].positions.capacity() + batches_[1].positions.capacity()) * sizeof(float) +
        (batches_[0].offsets.capacity() + batches_[1].offsets.capacity()) * sizeof(std::uint64_t);
    budget_.track(bytes, batch_held_, [&] {
      return "reading two batches of streamlines, one holding streamline " + std::to_string(longest_index_) + " (" +
             std::to_string(longest_) + " points) whole,";
    });
    report(stage, double(stream_->position()) / size);
  }
  report(stage, 1.0);
}

void StreamingConversion::open_stream() {
  const std::uint64_t limit = settings_.memory_limit;
  budget_.take(kBaselineBytes, "the program itself");
  const std::uint64_t read_buffer = std::clamp<std::uint64_t>(limit / 64, 64 << 10, 4 * kMiB);
  budget_.take(read_buffer, "the read buffer");
  batch_items_ = std::clamp<std::uint64_t>(limit / 64 / 16, 1024, 1 << 20);
  stream_ = std::make_unique<TckStream>(path_, std::max<std::uint64_t>(1, budget_.left() / 4), read_buffer);
  max_points_held_ = budget_.left() / kHeldBytesPerPoint;
}

// Pass 1: what plan_voxels' bounds scan finds, and the source's checksum and warnings.
void StreamingConversion::scan() {
  detail::BoundsScan bounds;
  std::uint64_t streamlines = 0, points = 0;
  each_batch("reading", [&](const Tractogram& b, std::uint64_t first) {
    for (std::uint64_t k = 0; k < b.streamline_count(); ++k)
      if (b.offsets[k + 1] - b.offsets[k] > longest_) {
        longest_ = b.offsets[k + 1] - b.offsets[k];
        longest_index_ = first + k;
      }
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
  each_batch("voxelising", [&](const Tractogram& b, std::uint64_t first) {
    const std::array<std::uint64_t, 3> cut = two_parts(b);
    // The voxels the limit leaves room for in this batch, half to each part: a part that would need more
    // fails (no matter how many the other adds, so that the outcome does not depend on timing).
    const std::uint64_t room = (plan_held_ + budget_.left()) / plan_bytes_per_voxel(settings_.levels);
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
    budget_.track(peak * plan_bytes_per_voxel(levels), plan_held_, [] { return std::string(); });
    other = PlanPart{Sink(), detail::VoxelUse(levels), {}, 0, 0};
    budget_.shrink(main.sink.index.coords().size() * plan_bytes_per_voxel(levels), plan_held_);
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
  const std::uint64_t bytes_per_voxel = plan_bytes_per_voxel(settings_.levels);
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

// Consecutive voxels, as many per range as fit in what the limit leaves: each range's vertices (packed:
// 4 bytes each, the end bit inside; float32: 12 bytes and an end bit; written block by block: only the
// float32 end bits) and its ordering threads' buffers.
// The orders are not held per range: they are built and written a chunk of voxels at a time (the chunk
// buffer is taken before this). An ordering thread's buffers grow with the largest voxel, so a range
// orders with fewer threads when they would take more than a quarter of the room (the orders do not
// depend on the thread count).
std::vector<Range> StreamingConversion::cut_ranges() {
  const std::uint64_t room = budget_.left();
  auto per_thread = [&](const Range& r) {
    return order_scratch_bytes(r.max_vertices) + end_bits_bytes(r.max_vertices);
  };
  auto order_threads = [&](const Range& r) {
    return static_cast<unsigned>(std::clamp<std::uint64_t>(room / 4 / per_thread(r), 1, threads_));
  };
  auto cost = [&](const Range& r) {
    const std::uint64_t v = r.vertex_end - r.vertex_first;
    const std::uint64_t end_bits = packed() ? 0 : (v / 64 + 1) * 8;
    const std::uint64_t held = block_staging_ > 0 ? end_bits : (packed() ? 4 : 12) * v + end_bits;
    return held + order_threads(r) * per_thread(r);
  };
  auto alone = [&](std::size_t i) {
    const VoxelEntry& v = voxels_[i];
    Range r{i, i + 1, v.vertex_first, v.vertex_first + v.vertex_count, v.vertex_count};
    if (cost(r) > room) {
      budget_.take(cost(r),
                   "voxel (" + std::to_string(v.coord[0]) + ", " + std::to_string(v.coord[1]) + ", " +
                       std::to_string(v.coord[2]) + ") of " + std::to_string(v.vertex_count) +
                       " vertices, with its sort buffers,",
                   ", or a smaller --voxel-size");
    }
    return r;
  };
  std::vector<Range> ranges;
  Range r;  // empty: the last one when there are no voxels (its pass still writes the tables)
  for (std::size_t i = 0; i < voxels_.size(); ++i) {
    if (r.first == r.end) {
      r = alone(i);
      continue;
    }
    Range grown = r;
    grown.end = i + 1;
    grown.vertex_end = voxels_[i].vertex_first + voxels_[i].vertex_count;
    grown.max_vertices = std::max(grown.max_vertices, voxels_[i].vertex_count);
    if (cost(grown) <= room) {
      r = grown;
    } else {
      ranges.push_back(r);
      r = alone(i);
    }
  }
  ranges.push_back(r);
  for (Range& each : ranges) each.order_threads = order_threads(each);
  return ranges;
}

// Pass 2 + k: the blocks and orders of one range.
void StreamingConversion::build_range(const Range& r, std::size_t index, std::size_t count) {
  const std::string of = " " + std::to_string(index + 1) + "/" + std::to_string(count);
  const bool tables = index == 0;
  const std::uint64_t range_vertices = r.vertex_end - r.vertex_first;
  if (block_staging_ > 0) {  // VERT written block by block, then read back for the orders
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
void StreamingConversion::place_range(const Range& r, bool tables, const std::string& of,
                                      std::span<std::uint8_t> window) {
  auto t0 = Clock::now();
  RangePlacement placing(r, tables, window);
  if (block_staging_ > 0) open_block_writers(placing);
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
  each_batch("placing" + of, [&](const Tractogram& b, std::uint64_t first) {
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
  const Range& r = placing.range;
  const std::uint32_t levels = settings_.levels;
  const std::uint64_t bytes = vertex_bytes(settings_.positions);
  placing.blocks.resize(cursor_.size());
  std::uint8_t* staging = pool_.get();  // the queue's spares, then each block's staging, one after another
  std::vector<std::uint8_t*> spares;
  for (std::uint64_t k = 0; k < kSpareBlockStagings; ++k, staging += block_staging_) spares.push_back(staging);
  placing.queue = out_->write_queue(std::move(spares), block_staging_);
  for (std::size_t local = 0; local < global_id_.size(); ++local) {
    const std::uint32_t g = global_id_[local];
    if (g < r.first || g >= r.end) continue;
    for (std::uint32_t d = 0; d < levels; ++d) {
      const std::uint64_t first = cursor_[local * levels + d];
      const std::uint64_t end =
          voxels_[g].vertex_first + depth_end_vertex(voxels_[g], level_row(levels_, g, levels), d);
      if (end > first) {
        const std::uint64_t size = DirectRegionWriter::staging_size((end - first) * bytes, block_staging_);
        if (std::uint64_t(staging - pool_.get()) + size > pool_bytes_)
          throw std::logic_error("StreamingConversion: the blocks' staging outgrows its pool");
        placing.blocks[local * levels + d] = out_->region_writer(
            VxlStreamWriter::kVert, first * bytes, (end - first) * bytes, block_staging_, staging, placing.queue.get());
        staging += size;
      }
    }
  }
}

// On one thread: voxelises streamlines [begin, end) of batch b (numbered from `first` in the source) and
// stages the vertices of their voxlines in range, packed (or as float32), in streamline order.
void StreamingConversion::stage_part(const RangePlacement& placing, const Tractogram& b, std::uint64_t first,
                                     std::uint64_t begin, std::uint64_t end, StagedPart& part) const {
  const Range& r = placing.range;
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
  const Range& r = placing.range;
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
void StreamingConversion::write_orders(const Range& r, std::span<const std::uint8_t> range_vertices,
                                       const std::string& stage) {
  // Per ordering thread, sized for the range's largest voxel once (fresh pages are dear; see above).
  std::vector<std::optional<VoxelOrderWriter>> writers(r.order_threads);
  std::vector<VoxlineEnds> block_ends(r.order_threads);
  std::vector<std::size_t> cuts{r.first};  // chunk c: voxels [cuts[c], cuts[c + 1])
  while (cuts.back() < r.end) {
    const std::size_t first = cuts.back();
    std::size_t end = first + 1;
    while (end < r.end && orders_start(end + 1) - orders_start(first) <= order_chunk_bytes_) ++end;
    cuts.push_back(end);
  }
  auto vertex_start = [&](std::size_t i) { return i < r.end ? voxels_[i].vertex_first : r.vertex_end; };
  const std::uint64_t vertex_size = vertex_bytes(settings_.positions);
  // The chunks' orders and the vertices read back: in pool_ after the blocks' staging is done with.
  std::unique_ptr<std::uint8_t[]> own_chunks[2];
  std::uint8_t* chunks[2] = {};
  std::span<std::uint8_t> read_buffers[2];
  if (block_staging_ > 0) {
    for (int b = 0; b < 2; ++b) {
      chunks[b] = pool_.get() + b * pool_chunk_bytes_;
      read_buffers[b] = {pool_.get() + 2 * pool_chunk_bytes_ + b * pool_read_back_bytes_, pool_read_back_bytes_};
    }
  }
  auto fetch = [&](std::size_t c) {
    return std::async(block_staging_ > 0 ? std::launch::async : std::launch::deferred, [&, c] {
      const std::uint64_t from = vertex_start(cuts[c]), to = vertex_start(cuts[c + 1]);
      if (block_staging_ == 0)
        return range_vertices.subspan((from - r.vertex_first) * vertex_size, (to - from) * vertex_size);
      return out_->read_back(VxlStreamWriter::kVert, (to - from) * vertex_size, read_buffers[c % 2]);
    });
  };
  // With direct writes a chunk is written on its own thread while the next one is built (the write waits
  // on the disk, not the CPU); through the page cache it is written before the next one is built.
  // The buffers are taken once at the largest chunk's size and not cleared: the writers write every
  // byte of their voxels' orders, padding included. (Regrowing and zeroing them per chunk took 3 of the
  // 11 s of a 10M conversion's orders: fresh pages cost much on a virtual machine.)
  std::vector<std::size_t> by_size;  // a chunk's voxels
  std::future<std::span<const std::uint8_t>> next_vertices;
  if (cuts.size() > 1) next_vertices = fetch(0);
  std::future<void> writing;
  for (std::size_t c = 0; c + 1 < cuts.size(); ++c) {
    auto t0 = Clock::now();
    const std::size_t first = cuts[c], end = cuts[c + 1];
    const std::span<const std::uint8_t> vertices = next_vertices.get();
    if (c + 2 < cuts.size()) next_vertices = fetch(c + 1);
    const std::uint64_t base = orders_start(first);
    const int b = direct_staging_ > 0 ? c % 2 : 0;
    if (chunks[b] == nullptr) {
      own_chunks[b] = std::make_unique_for_overwrite<std::uint8_t[]>(order_chunk_bytes_);
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
    if (direct_staging_ > 0)
      writing = std::async(std::launch::async, [this, chunk] { out_->append(VxlStreamWriter::kOrdr, chunk); });
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
void StreamingConversion::write_voxel_orders(const Range& r, std::size_t g, std::span<const std::uint8_t> vertices,
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

std::uint64_t StreamingConversion::block_staging_total(std::uint64_t staging) const {
  const std::uint32_t levels = settings_.levels;
  const std::uint64_t bytes = vertex_bytes(settings_.positions);
  std::uint64_t total = kSpareBlockStagings * staging;  // the write queue's spares
  for (std::size_t g = 0; g < voxels_.size(); ++g) {
    const std::span<const LevelEntry> row = level_row(levels_, g, levels);
    for (std::uint32_t d = 0; d < levels; ++d) {  // as open_block_writers cuts them
      const std::uint64_t first = depth_first_vertex(row, d), end = depth_end_vertex(voxels_[g], row, d);
      if (end > first) total += DirectRegionWriter::staging_size((end - first) * bytes, staging);
    }
  }
  return total;
}

std::uint64_t StreamingConversion::largest_chunk_vertex_bytes() const {
  std::uint64_t most = 0;
  std::size_t end = 0;  // the end of the longest chunk from `first`: never decreases as `first` grows
  for (std::size_t first = 0; first < voxels_.size(); ++first) {
    end = std::max(end, first + 1);
    while (end < voxels_.size() && orders_start(end + 1) - orders_start(first) <= order_chunk_bytes_) ++end;
    const VoxelEntry& last = voxels_[end - 1];
    most = std::max(most, last.vertex_first + last.vertex_count - voxels_[first].vertex_first);
  }
  return most * vertex_bytes(settings_.positions);
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
  budget_.take(kTableBufferEntries * (sizeof(VoxlineEntry) + sizeof(std::uint64_t)),
               "the buffer of the voxline and streamline tables");
  budget_.take(meta_.streamline_count * sizeof(spans_[0]), "the voxel span of every streamline");
  spans_.resize(meta_.streamline_count);
  // The parts of two batches being placed (StagedPart), from what pass 2 counted per point: a voxline
  // entry (24 bytes) per voxline, a voxline end (8) per streamline and a staged vertex per vertex, twice
  // for the vectors' growth. A batch that needs more (a long streamline is held whole) takes the rest
  // when it comes, while the limit allows.
  {
    const double points = double(std::max<std::uint64_t>(1, meta_.point_count));
    const double vertices = double(meta_.point_count + meta_.synthetic_point_count + meta_.voxline_count);
    const double per_point = (24.0 * double(meta_.voxline_count) + 8.0 * double(meta_.streamline_count) +
                              double(vertex_bytes(settings_.positions)) * vertices) /
                             points;
    staged_held_ = static_cast<std::uint64_t>(2 * 2 * per_point * double(batch_items_));
    budget_.take(staged_held_, "the voxlines of two batches being placed");
  }
  // Direct writes (the output bypasses the page cache) where the limit leaves room for their staging.
  if (settings_.memory_limit >= kDirectWritesFromLimit) {
    direct_staging_ = kDirectStagingBytes;
    budget_.take(VxlStreamWriter::kCount * kDirectStagingBytes, "the staging of the output's direct writes");
  }
  order_chunk_bytes_ = std::min(
      {tuning_.order_chunk_bytes > 0 ? tuning_.order_chunk_bytes : kOrderChunkBytes, order_bytes_, budget_.left() / 8});
  for (std::size_t i = 0; i < voxels_.size(); ++i)
    order_chunk_bytes_ = std::max(order_chunk_bytes_, orders_start(i + 1) - orders_start(i));
  if (direct_staging_ > 0) {
    // VERT block by block when the blocks' staging takes at most an eighth of what is left and the pool
    // (that staging, then two orders chunks and two chunks' vertices read back) at most half.
    constexpr std::uint64_t block = DirectRegionWriter::kBlock;
    pool_chunk_bytes_ = (order_chunk_bytes_ + block - 1) / block * block;
    pool_read_back_bytes_ = VxlStreamWriter::read_back_bytes(largest_chunk_vertex_bytes());
    for (std::uint64_t staging = kBlockStagingBytes; staging >= kMinBlockStagingBytes && block_staging_ == 0;
         staging /= 2) {
      const std::uint64_t total = block_staging_total(staging);
      if (total <= budget_.left() / 8 &&
          std::max(total, 2 * (pool_chunk_bytes_ + pool_read_back_bytes_)) <= budget_.left() / 2)
        block_staging_ = staging;
    }
  }
  if (block_staging_ > 0) {
    pool_bytes_ = std::max(block_staging_total(block_staging_), 2 * (pool_chunk_bytes_ + pool_read_back_bytes_));
    budget_.take(pool_bytes_, "the vertex blocks being written, then the orders being built and their vertices");
    void* p = std::aligned_alloc(DirectRegionWriter::kBlock, pool_bytes_);
    if (p == nullptr) throw std::bad_alloc();
    pool_.reset(static_cast<std::uint8_t*>(p));
  } else {
    budget_.take(order_chunk_bytes_ * (direct_staging_ > 0 ? 2 : 1), "the part of the orders being written",
                 ", or a smaller --voxel-size");
  }
  std::vector<Range> ranges = cut_ranges();

  const std::string provenance = provenance_json(stream_->source(), settings_, threads_, voxel_size_choice_);
  out_ = std::make_unique<VxlStreamWriter>(out_path_, section_sizes(meta_, order_bytes_, provenance.size(), 0),
                                           direct_staging_);
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
  summary_.partitions = ranges.size();
  summary_.vertices_read_back = block_staging_ > 0;
  for (const Range& r : ranges) summary_.partition_starts.push_back(r.first);
  summary_.warnings = stream_->source().warnings;
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
