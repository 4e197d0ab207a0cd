// The streaming conversion's first two passes: the scan (bounds, checksum, warnings) and the counts and
// tight bounds per voxel, then the voxel table made of them (streaming_conversion.h).
#include "converter/pipeline/streaming_conversion.h"

#include <algorithm>
#include <array>
#include <utility>

#include "converter/convert/voxel_size_auto.h"
#include "format/base/parallel.h"

namespace vxl::streaming {

// Pass 1: the bounds, the longest step and each streamline's length (BoundsScan), and the source's checksum and
// warnings.
void StreamingConversion::scan() {
  detail::BoundsScan bounds;
  std::uint64_t streamlines = 0, points = 0;
  BatchCut cut{};
  std::array<detail::BoundsScan, kBatchParts> parts;
  const auto prepare = [&](const Tractogram& b, std::uint64_t first, int) {
    reader_->note_longest(b, first);
    std::vector<float>& lengths = scan_.lengths;
    const std::uint64_t need = first + b.streamline_count();
    if (need > lengths.capacity()) {  // taken from the limit before it is allocated
      const std::uint64_t grown = std::max<std::uint64_t>(need, 2 * lengths.capacity());
      budget_.track(grown * sizeof(float), scan_.lengths_held, [] { return "the streamlines' lengths"; });
      lengths.reserve(grown);
    }
    lengths.resize(need);
    cut = cut_batch(b);
    parts.fill(detail::BoundsScan());
  };
  // The parts are merged in order (a scan stops at a bad point; reading goes on for the reader's errors).
  const auto scan_part = [&](const Tractogram& b, std::uint64_t first, std::uint64_t p, int) {
    parts[p].add(b.positions.data(), b.offsets.data(), cut[p], cut[p + 1], first, scan_.lengths.data() + first);
  };
  const auto finish = [&](const Tractogram& b, std::uint64_t, int) {
    for (const detail::BoundsScan& part : parts) bounds.merge(part);
    streamlines += b.streamline_count();
    points += b.point_count();
  };
  reader_->each_batch(
      "reading", {kBatchParts}, prepare, scan_part, [](std::uint64_t, int) {}, finish);
  bounds.check(job_.path);
  for (int c = 0; c < 3; ++c) {
    scan_.lo[c] = bounds.lo[c];
    scan_.hi[c] = bounds.hi[c];
  }
  scan_.longest_step2 = bounds.longest_step2;
  table_.meta.streamline_count = streamlines;
  table_.meta.point_count = points;
  if (job_.settings.voxel_size_auto) {
    const VoxelSizeChoice choice = choose_voxel_size(points, scan_.lo, scan_.hi, bounds.rms_step(), job_.path);
    job_.settings.voxel_size = choice.size;
    job_.voxel_size_choice = choice.reason;
  }
  table_.meta.voxel_size = job_.settings.voxel_size;
}

// Pass 2: the vertex and segment counts and the tight bounds per voxel, kept per voxel only. Each batch is cut in parts
// (cut_batch) counted side by side: the first into the source's voxel index (table_.sink, counting_.use,
// counting_.bounds), the others into indexes of their own (PlanPart), folded into it after the batch — the counts and
// bounds do not depend on the order streamlines are counted in.
void StreamingConversion::count_voxels() {
  counting_.use = detail::VoxelUse(job_.settings.levels);
  if (table_.meta.point_count == 0) {  // no voxels
    counting_.recording_runs = false;
    return;
  }
  table_.grid = detail::set_grid(table_.meta, scan_.lo, scan_.hi, job_.path);
  // The limit on added points, applied to the whole source (so that the outcome does not depend on the threads).
  table_.synthetic_limit = static_cast<std::uint64_t>(kMaxSyntheticPerPoint * double(table_.meta.point_count)) + 4096;
  const std::uint32_t levels = job_.settings.levels;
  // Part 0 counts into the source's voxel index; the others into indexes of their own, folded into it
  // after each batch.
  const auto empty_part = [&] { return PlanPart{Sink(), detail::VoxelUse(levels), {}, 0, 0, {}}; };
  std::array<PlanPart, kBatchParts> parts;
  parts[0] = PlanPart{std::move(table_.sink), std::move(counting_.use), std::move(counting_.bounds), 0, 0, {}};
  for (std::size_t p = 1; p < kBatchParts; ++p) parts[p] = empty_part();
  PlanPart& main = parts[0];
  std::uint64_t voxlines = 0, synthetic = 0, points = 0;
  BatchCut cut{};
  std::array<std::uint64_t, kBatchParts> most{};
  std::uint64_t start = 0;
  const auto prepare = [&](const Tractogram& b, std::uint64_t, int) {
    cut = cut_batch(b);
    // The voxels the limit leaves room for in this batch, shared among the parts: a part that would need
    // more fails (no matter how many the others add, so that the outcome does not depend on timing).
    // (The runs give their memory back when the table needs it.)
    const std::uint64_t room =
        (counting_.table_held + table_.runs_held + budget_.left()) / voxel_table_bytes_per_voxel(levels);
    start = main.sink.index.coords().size();
    const std::uint64_t headroom = room > start ? room - start : 0;
    for (std::size_t p = 0; p < kBatchParts; ++p) most[p] = headroom / kBatchParts;
    most[0] += start + headroom % kBatchParts;
  };
  // The sink: the earlier batch's voxel runs appended to table_.runs (beside this batch's parts rather than on one
  // thread between the rounds: 0.5 s of the 10M set's counting pass). Handed out after the parts.
  PendingRuns pending;
  const auto count = [&](const Tractogram& b, std::uint64_t first, std::uint64_t p, int) {
    count_part(b, first, cut[p], cut[p + 1], points, synthetic, most[p], p == 0 ? 0 : start, parts[p]);
  };
  const auto append = [&](std::uint64_t, int) { append_runs(pending); };
  const auto finish = [&](const Tractogram& b, std::uint64_t first, int) {
    for (PlanPart& part : parts) {
      voxlines += std::exchange(part.voxlines, 0);
      synthetic += std::exchange(part.synthetic, 0);
    }
    if (synthetic > table_.synthetic_limit)
      detail::fail_too_many_synthetic(job_.path, table_.meta.voxel_size, scan_.longest_step2, table_.synthetic_limit);
    // Every part's table at its largest (within the limit, by the parts' shares); then the other parts'
    // voxels into the first's index.
    std::uint64_t peak = 0, sinks = 0;
    for (const PlanPart& part : parts) {
      peak += part.sink.index.coords().size();
      sinks += part.sink.bytes();
    }
    std::array<std::vector<std::uint32_t>, kBatchParts> local_ids;  // part p's local ids in the first's index
    for (std::size_t p = 1; p < kBatchParts; ++p) local_ids[p] = fold_into_first(main, parts[p]);
    if (counting_.recording_runs) hold_runs(parts, pending);  // which may drop them
    if (counting_.recording_runs) {                           // this batch's runs wait for the next round (or the end)
      for (std::size_t p = 0; p < kBatchParts; ++p) {
        std::swap(parts[p].runs, pending.runs[p]);
        pending.first[p] = first + cut[p];
      }
      pending.local_ids = std::move(local_ids);
      pending.waiting = true;
    }
    const std::uint64_t table_peak = peak * voxel_table_bytes_per_voxel(levels);
    if (table_peak > counting_.table_held && table_peak - counting_.table_held + sinks > budget_.left()) {
      drop_runs();
      pending = PendingRuns();
      main.runs = {};
    }
    budget_.track(table_peak, counting_.table_held, [] { return std::string(); });
    for (std::size_t p = 1; p < kBatchParts; ++p) {  // the runs' list keeps its memory for the next batch
      std::vector<VoxelRun> runs = std::move(parts[p].runs);
      parts[p] = empty_part();
      if (counting_.recording_runs) parts[p].runs = std::move(runs);
    }
    budget_.shrink(main.sink.index.coords().size() * voxel_table_bytes_per_voxel(levels), counting_.table_held);
    budget_.track(sinks, counting_.sink_held, [] { return std::string("the voxline lists of the batch's parts"); });
    points += b.point_count();
  };
  static_assert(kBatchParts == 3);
  constexpr std::array<std::uint64_t, kBatchParts + 1> kPartsFirst = {1, 2, 3, 0};
  reader_->each_batch("voxelising", {kBatchParts, 1, kPartsFirst}, prepare, count, append, finish);
  if (counting_.recording_runs) hold_runs(parts, pending);  // the last batch's runs, appended by the last sink
  table_.sink = std::move(main.sink);
  counting_.use = std::move(main.use);
  counting_.bounds = std::move(main.bounds);
  table_.meta.voxline_count = voxlines;
  table_.meta.synthetic_point_count = synthetic;
}

// Folds `other`'s voxels, counts and bounds into `main`'s; returns each of its local ids' id in main's index.
std::vector<std::uint32_t> StreamingConversion::fold_into_first(PlanPart& main, const PlanPart& other) const {
  const std::uint32_t levels = job_.settings.levels;
  const std::vector<detail::Coord>& coords = other.sink.index.coords();
  std::vector<std::uint32_t> ids(coords.size());
  for (std::uint32_t j = 0; j < coords.size(); ++j) {
    const std::uint32_t i = ids[j] = main.sink.index.find_or_insert(coords[j]);
    main.use.grow_to(main.sink.index.coords().size());
    main.bounds.grow_to(main.sink.index.coords().size());
    for (std::uint32_t d = 0; d < levels; ++d) {
      main.use.vertices[std::size_t(i) * levels + d] += other.use.vertices[std::size_t(j) * levels + d];
      main.use.segments[std::size_t(i) * levels + d] += other.use.segments[std::size_t(j) * levels + d];
    }
    main.bounds.merge(i, other.bounds, j);
  }
  return ids;
}

// Appends a batch's runs to table_.runs, part by part (each part's from its first streamline on, those of parts
// past the first with the first part's local ids), and empties their lists (their memory is kept for a later
// batch). Nothing when none are waiting.
void StreamingConversion::append_runs(PendingRuns& pending) {
  if (!pending.waiting) return;
  VoxelRuns& runs = table_.runs;
  for (std::size_t p = 0; p < kBatchParts; ++p) {
    runs.start_part(pending.first[p]);
    if (p > 0)
      for (VoxelRun& r : pending.runs[p])
        if (r.voxel != VoxelRuns::kVoxelisedAgain) r.voxel = pending.local_ids[p][r.voxel];
    runs.append(pending.runs[p]);
    pending.runs[p].clear();
  }
  pending.waiting = false;
}

// Keeps recording the runs while they take at most half of what the limit leaves (the rest is the voxel table's
// and the plan's), else drops them. The lists of the batch just counted count with them, and the memory the
// earlier batch's lists keep for the next one.
void StreamingConversion::hold_runs(std::span<PlanPart, kBatchParts> parts, PendingRuns& pending) {
  std::uint64_t lists = 0;
  for (std::size_t p = 0; p < kBatchParts; ++p)
    lists += (parts[p].runs.capacity() + pending.runs[p].capacity()) * sizeof(VoxelRun);
  const std::uint64_t held = table_.runs.bytes() + lists;
  if (held > table_.runs_held && held - table_.runs_held > budget_.left() / 2) {
    drop_runs();
    for (PlanPart& part : parts) part.runs = {};
    pending = PendingRuns();
  } else {
    budget_.track(held, table_.runs_held, [] { return std::string("the voxel runs"); });
  }
}

// Stops recording the runs and gives back their memory: the placing passes voxelise again.
void StreamingConversion::drop_runs() {
  counting_.recording_runs = false;
  table_.runs.clear();
  budget_.shrink(0, table_.runs_held);
}

// On one thread: counts streamlines [begin, end) of batch b (numbered from `first`) into `part`, whose
// index may grow to `most_voxels` (its share of the limit; checked after every streamline, so that a table
// outgrowing the limit is caught before it goes far past it); `other_voxels` are the first part's at the
// batch's start (for the others' message). `points` and `synthetic` are those of the batches before.
void StreamingConversion::count_part(const Tractogram& b, std::uint64_t first, std::uint64_t begin, std::uint64_t end,
                                     std::uint64_t points, std::uint64_t synthetic, std::uint64_t most_voxels,
                                     std::uint64_t other_voxels, PlanPart& part) const {
  const float* pts = b.positions.data();
  const std::uint64_t bytes_per_voxel = voxel_table_bytes_per_voxel(job_.settings.levels);
  for (std::uint64_t k = begin; k < end; ++k) {
    part.sink.clear();
    detail::voxelize_streamline(table_.grid, pts, b.offsets[k], b.offsets[k + 1] - b.offsets[k], part.sink,
                                table_.synthetic_limit - std::min(table_.synthetic_limit, synthetic + part.synthetic));
    if (part.sink.too_many_synthetic)
      detail::fail_too_many_synthetic(job_.path, table_.meta.voxel_size, scan_.longest_step2, table_.synthetic_limit);
    part.synthetic += part.sink.synthetic_xyz.size() / 3;
    if (counting_.recording_runs) {
      if (!part.sink.synthetic_xyz.empty())
        part.runs.push_back({VoxelRuns::kVoxelisedAgain, 0});
      else
        for (const TempVoxline& v : part.sink.voxlines) part.runs.push_back({v.voxel, v.src_count});
    }
    const std::size_t n_local = part.sink.index.coords().size();
    part.use.grow_to(n_local);
    detail::count_voxel_use(part.sink.voxlines, streamline_depth(first + k, job_.settings.levels), part.use, job_.path);
    part.bounds.grow_to(n_local);
    for (std::size_t j = 0; j < part.sink.voxlines.size(); ++j)
      part.bounds.add_voxline(part.sink.voxlines, j, pts, part.sink.synthetic_xyz.data());
    part.voxlines += part.sink.voxlines.size();
    if (n_local > most_voxels) {
      const std::uint64_t voxels = n_local + other_voxels;
      // Voxels turn up ever more slowly: extrapolating from the points read so far overestimates.
      const std::uint64_t read = points + b.offsets[k + 1];
      const std::uint64_t all =
          static_cast<std::uint64_t>(double(voxels) * double(table_.meta.point_count) / double(read));
      budget_.fail(all * bytes_per_voxel, budget_.used() - counting_.table_held - table_.runs_held,
                   "the voxel table (" + std::to_string(voxels) + " voxels after " + std::to_string(read) + " of " +
                       std::to_string(table_.meta.point_count) + " points; about " + std::to_string(all) +
                       " in all, extrapolated)",
                   ", or a larger --voxel-size");
    }
  }
}

// The voxel table sorted by (z, y, x), laid out for the orders (layout_orders).
void StreamingConversion::build_table() {
  detail::LocalVoxels table{&table_.sink.index.coords(), &counting_.use, {}, {}};
  counting_.use.grow_to(table_.sink.index.coords().size());
  detail::VoxelTable built = detail::build_voxel_table({&table, 1}, job_.settings.levels, table_.meta, job_.path);
  table_.voxels = std::move(built.voxels);
  table_.levels = std::move(built.levels);
  counting_.use = detail::VoxelUse(job_.settings.levels);
  table_.global_id = std::move(table.global_id);
  table_.cursor = std::move(table.cursor);
  for (std::uint32_t local = 0; local < table_.global_id.size(); ++local)
    counting_.bounds.set_tight_bounds(local, table_.voxels[table_.global_id[local]]);
  counting_.bounds = detail::VoxelBounds();
  table_.meta.stored_order_count = static_cast<std::uint32_t>(job_.order_set.directions.size());
  table_.meta.order_set = static_cast<std::uint32_t>(job_.order_set.kind);
  table_.meta.position_encoding = static_cast<std::uint32_t>(job_.settings.positions);
  table_.order_bytes =
      layout_orders(table_.voxels, table_.levels, job_.settings.levels, table_.meta.stored_order_count);
}

}  // namespace vxl::streaming
