// The streaming conversion's pass per range of voxels: the range's vertices placed into VERT (mapped, or
// written block by block through stagings), and the voxline and streamline tables with the first range
// (streaming_conversion.h).
#include "converter/pipeline/streaming_conversion.h"

#include <algorithm>
#include <array>
#include <limits>
#include <optional>
#include <stdexcept>

#include "format/base/parallel.h"

namespace vxl::streaming {

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
      VxlStreamWriter::kVert, range_vertices * vertex_bytes(job_.settings.positions), job_.threads,
      [&](std::span<std::uint8_t> window) { place_range(r, tables, of, window); },
      [&](std::span<const std::uint8_t> window) { write_orders(r, window, "ordering" + of); });
}

// Range r's orders (range_orders.h) from its vertices in memory, or read back into the pool.
void StreamingConversion::write_orders(const VoxelRange& r, std::span<const std::uint8_t> range_vertices,
                                       const std::string& stage) {
  RangeOrderSettings settings;
  settings.order_set = &job_.order_set;
  settings.positions = job_.settings.positions;
  settings.order_chunk_bytes = plan_.order_chunk_bytes;
  settings.direct = plan_.direct_staging_bytes > 0;
  settings.float_ends = &ends_;
  if (plan_.block_staging_bytes > 0) {
    settings.pool = pool_.get();
    settings.pool_chunk_bytes = plan_.pool_chunk_bytes;
    settings.pool_read_back_bytes = plan_.pool_read_back_bytes;
  }
  settings.progress = [&](double fraction) { report(stage, fraction); };
  const OrderedTable table{table_.voxels, table_.levels, job_.settings.levels, table_.order_bytes};
  summary_.orders_seconds += write_range_orders(*out_, table, r, range_vertices, settings);
}

// Pass 2 + k, reading: places range r's vertices in `window` (its part of VERT); the first range also
// writes the voxline and streamline tables. Each batch is cut in parts that are voxelised and packed
// side by side (stage_part: packing needs only the voxel, whose tight bounds came from pass 2),
// then placed in streamline order (place_part), which is what fixes where each vertex goes.
void StreamingConversion::place_range(const VoxelRange& r, bool tables, const std::string& of,
                                      std::span<std::uint8_t> window) {
  auto t0 = Clock::now();
  std::vector<std::uint64_t> ends = block_ends(r);
  RangePlacement placing(r, tables, open_vertex_sink(window, ends));
  placing.block_end = std::move(ends);
  if (packed()) {
    placing.packers.reserve(r.end - r.first);
    for (std::size_t g = r.first; g < r.end; ++g) placing.packers.emplace_back(table_.voxels[g]);
  } else {
    ends_ = VoxlineEnds(r.vertex_end - r.vertex_first);
  }
  if (tables) placing.table_appender.emplace(*out_, plan_.table_buffer_entries);
  // Batch k is staged in parts (cut_batch) while batch k - 1, staged before, is placed in streamline order.
  // With packed positions the placing is split too, at a voxel that halves the range's vertices: each half
  // places the voxlines of its own voxels (their blocks are apart), the first also writes the tables. The
  // items share the reader's threads as they come free; float32 positions place in one item (their voxline
  // ends are bits that neighbouring blocks share).
  placing.split = r.end;
  if (packed() && job_.threads > 1 && r.end - r.first > 1) {
    const std::uint64_t middle = r.vertex_first + (r.vertex_end - r.vertex_first) / 2;
    const auto voxels = std::span<const VoxelEntry>(table_.voxels).subspan(r.first + 1, r.end - r.first - 1);
    placing.split =
        r.first + 1 +
        static_cast<std::size_t>(std::partition_point(voxels.begin(), voxels.end(),
                                                      [&](const VoxelEntry& v) { return v.vertex_first < middle; }) -
                                 voxels.begin());
  }
  const bool split = placing.split < r.end;
  const bool index = tables && table_.index_lists;  // the first range fills the voxel index's lists
  BatchCut cut{};
  const auto prepare = [&](const Tractogram& b, std::uint64_t first, int) {
    if (first + b.streamline_count() > table_.spans.size()) fail_changed();  // more streamlines than pass 1 counted
    cut = cut_batch(b);
  };
  const auto stage = [&](const Tractogram& b, std::uint64_t first, std::uint64_t p, int slot) {
    stage_part(placing, b, first, cut[p], cut[p + 1], placing.parts[slot][p]);
  };
  // The sink, in streamline order: the earlier batch placed in its halves (items 0 and 1), then added to the voxel
  // index's lists (item 2), so that its errors come first. Handed out after the staging parts (on the 10M set 4-5 ms
  // each, a half 3-3.5 ms, the index 1.2 ms): handed out first, the last staging part ran alone at the end of every
  // batch.
  const auto place = [&](std::uint64_t item, int slot) {
    if (item == 2) {
      if (index)
        for (const StagedPart& part : placing.parts[slot]) index_part(part);
    } else if (item == 0 || split) {
      for (const StagedPart& part : placing.parts[slot]) place_part(placing, part, static_cast<int>(item));
    }
  };
  const auto finish = [&](const Tractogram&, std::uint64_t, int) {
    std::uint64_t staged = 0;
    for (const auto& set : placing.parts)
      for (const StagedPart& part : set) staged += part.bytes();
    budget_.track(staged, staged_held_, [] { return std::string("the voxlines of two batches being placed"); });
  };
  static_assert(kBatchParts == 3);
  constexpr std::array<std::uint64_t, 3 + kBatchParts> kStagingFirst = {3, 4, 5, 0, 1, 2};
  reader_->each_batch("placing" + of, {kBatchParts, 3, kStagingFirst}, prepare, stage, place, finish);
  placing.sink.finish();  // rethrows a failed write (each block's completeness is checked below)
  if (placing.streamlines != table_.meta.streamline_count ||
      (tables && placing.voxline_index != table_.meta.voxline_count) ||
      (tables && table_.index_lists && !table_.index_lists->complete()))
    fail_changed();
  const std::uint32_t levels = job_.settings.levels;
  for (std::size_t local = 0; local < table_.global_id.size(); ++local) {
    const std::uint32_t g = table_.global_id[local];
    if (g < r.first || g >= r.end) continue;
    for (std::uint32_t d = 0; d < levels; ++d)
      if (table_.cursor[local * levels + d] != placing.block_end[local * levels + d]) fail_changed();
  }
  if (tables) {
    placing.table_appender->add_streamline(placing.voxline_index);
    placing.table_appender->finish();
  }
  if (tables && table_.index_lists) {  // written now, so that the orders do not build beside their memory
    out_->append_voxel_index(*table_.index_lists);
    table_.index_lists.reset();
    budget_.shrink(0, table_.index_lists_held);
  }
  if (r.end == table_.voxels.size()) {
    // The last range is placed: the voxel runs and spans serve no other pass, so their memory goes before the
    // orders are built beside the range's vertices (1M streamlines: 72 MiB of runs).
    table_.runs.clear();
    budget_.shrink(0, table_.runs_held);
    std::vector<std::array<std::uint32_t, 2>>().swap(table_.spans);
  }
  summary_.voxelize_seconds += seconds_since(t0);
}

// By (local id * levels + depth): where the block of each voxel of range r ends (its last vertex + 1); 0 for
// the voxels of other ranges.
std::vector<std::uint64_t> StreamingConversion::block_ends(const VoxelRange& r) const {
  const std::uint32_t levels = job_.settings.levels;
  std::vector<std::uint64_t> ends(table_.cursor.size(), 0);
  for (std::size_t local = 0; local < table_.global_id.size(); ++local) {
    const std::uint32_t g = table_.global_id[local];
    if (g < r.first || g >= r.end) continue;
    for (std::uint32_t d = 0; d < levels; ++d)
      ends[local * levels + d] =
          table_.voxels[g].vertex_first + depth_end_vertex(table_.voxels[g], level_row(table_.levels, g, levels), d);
  }
  return ends;
}

// Where a range's vertices go: `window` (its part of VERT), or, written block by block, a writer per
// (voxel, level) block of the range with vertices, from the block's first vertex (table_.cursor, before any
// is placed) to its end (`ends`, block_ends).
VertexSink StreamingConversion::open_vertex_sink(std::span<std::uint8_t> window,
                                                 std::span<const std::uint64_t> ends) const {
  const std::uint64_t bytes = vertex_bytes(job_.settings.positions);
  if (plan_.block_staging_bytes == 0) return VertexSink(window, bytes);
  std::vector<std::array<std::uint64_t, 2>> blocks(table_.cursor.size());  // {0, 0}: none in this range
  for (std::size_t k = 0; k < blocks.size(); ++k)
    if (ends[k] > 0) blocks[k] = {table_.cursor[k], ends[k]};
  return VertexSink(*out_, blocks, bytes, plan_.block_staging_bytes, kSpareBlockStagings, pool_.get(),
                    plan_.pool_bytes);
}

// On one thread: voxelises streamlines [begin, end) of batch b (numbered from `first` in the source) and
// stages the vertices of their voxlines in range, packed (or as float32), in streamline order, for the
// placing half of their voxel; in the first range also every voxline's table entry and each streamline's span.
void StreamingConversion::stage_part(const RangePlacement& placing, const Tractogram& b, std::uint64_t first,
                                     std::uint64_t begin, std::uint64_t end, StagedPart& part) const {
  const VoxelRange& r = placing.range;
  const std::uint32_t levels = job_.settings.levels;
  part.begin = begin;
  part.end = end;
  part.source_first = first + begin;
  part.sink.index.index = &table_.sink.index;
  for (int h = 0; h < 2; ++h) {
    part.voxlines[h].clear();
    part.words[h].clear();
    part.xyz[h].clear();
    part.values[h].clear();
  }
  part.table_entries.clear();
  part.streamline_voxlines.clear();
  part.spans.clear();
  const float* pts = b.positions.data();
  std::vector<float> voxline_xyz;  // one voxline's vertices on their way to being packed
  part.sink.too_many_synthetic = false;
  // The part's voxel runs, when pass 2 kept them (the same batches, cut the same way).
  std::uint64_t run = 0;
  if (table_.runs_kept && begin < end) {
    const std::optional<std::uint64_t> at = table_.runs.part_start(first + begin);
    if (!at) fail_changed();
    run = *at;
  }
  for (std::uint64_t k = begin; k < end; ++k) {
    part.sink.clear();
    const std::uint64_t points = b.offsets[k + 1] - b.offsets[k];
    const bool by_runs = table_.runs_kept && points > 0 &&
                         (run >= table_.runs.size() || table_.runs[run].voxel != VoxelRuns::kVoxelisedAgain);
    if (!placing.tables) {
      const std::array<std::uint32_t, 2>& span = table_.spans[first + k];
      if (span[1] < r.first || span[0] >= r.end) {  // no voxel in this range (or none at all)
        if (by_runs)
          cut_by_runs(b.offsets[k], points, run, part.sink.voxlines);
        else if (table_.runs_kept && points > 0)
          ++run;  // kVoxelisedAgain
        continue;
      }
    }
    if (by_runs) {
      cut_by_runs(b.offsets[k], points, run, part.sink.voxlines);
    } else {
      if (table_.runs_kept && points > 0) ++run;  // kVoxelisedAgain
      detail::voxelize_streamline(table_.grid, pts, b.offsets[k], points, part.sink, table_.synthetic_limit);
      if (part.sink.too_many_synthetic) fail_changed();
    }
    const std::span<const TempVoxline> streamline(part.sink.voxlines);
    const std::uint32_t depth = streamline_depth(first + k, levels);
    std::array<std::uint32_t, 2> span = {std::numeric_limits<std::uint32_t>::max(), 0};
    for (std::size_t j = 0; j < streamline.size(); ++j) {
      const TempVoxline& v = streamline[j];
      if (v.voxel >= table_.global_id.size()) fail_changed();  // a voxel pass 2 did not see
      const std::uint32_t g = table_.global_id[v.voxel];
      if (placing.tables) {
        span = {std::min(span[0], g), std::max(span[1], g)};
        part.table_entries.push_back({g, v.own() | (v.synthetic != kNoSynthetic ? kVoxlineSyntheticFirst : 0u)});
      }
      if (g < r.first || g >= r.end) continue;
      const std::uint64_t used = v.own() + (j + 1 < streamline.size() ? 1 : 0);
      const int half = g < placing.split ? 0 : 1;
      part.voxlines[half].push_back({v.voxel, static_cast<std::uint32_t>(used), depth});
      // Float32 vertices go straight to their half's array; packed ones through voxline_xyz.
      std::vector<float>& staged = packed() ? voxline_xyz : part.xyz[half];
      const std::size_t staged_at = packed() ? 0 : staged.size();
      staged.resize(staged_at + 3 * used);
      float* const xyz = staged.data() + staged_at;
      detail::place_voxline(streamline, j, pts, part.sink.synthetic_xyz.data(), xyz);
      if (!vertex_value_arrays_.empty())
        stage_values(part, streamline, j, used, job_.held->offsets[first], part.values[half]);
      // A vertex outside the bounds pass 2 found (packed: it would be clamped) means the source changed, also
      // where its size and time did not.
      const VoxelEntry& voxel = table_.voxels[g];
      for (std::uint64_t e = 0; e < used; ++e)
        for (int c = 0; c < 3; ++c)
          if (!(xyz[3 * e + c] >= voxel.tight_min[c] && xyz[3 * e + c] <= voxel.tight_max[c])) fail_changed();
      if (!packed()) continue;
      std::vector<std::uint32_t>& words = part.words[half];
      const std::size_t at = words.size();
      words.resize(at + used);
      placing.packers[g - r.first].words(voxline_xyz.data(), used, words.data() + at);
      words[at + used - 1] |= kPackedVoxlineEnd;
    }
    if (placing.tables) {
      part.streamline_voxlines.push_back(static_cast<std::uint32_t>(streamline.size()));
      part.spans.push_back(span);
    }
  }
}

// Appends to `out` the values of every set of the held source for the `used` vertices of voxline j of `streamline`
// (of a batch whose first point is the source's point `point_base`), as place_voxline lays the vertices out: an
// added point's value interpolated where it lies on its step, a connecting vertex's the next voxline's first.
void StreamingConversion::stage_values(const StagedPart& part, std::span<const TempVoxline> streamline, std::size_t j,
                                       std::uint64_t used, std::uint64_t point_base, std::vector<float>& out) const {
  const TempVoxline& v = streamline[j];
  for (const ValueSet& set : job_.held->point_values) {
    const float* src = set.values.data() + point_base;
    const auto first_value = [&](const TempVoxline& x) {
      if (x.synthetic == kNoSynthetic) return src[x.src_first];
      const double a = src[x.src_first - 1], b = src[x.src_first], at = part.sink.synthetic_t[x.synthetic];
      return static_cast<float>(a + at * (b - a));
    };
    const std::size_t at = out.size();
    if (v.synthetic != kNoSynthetic) out.push_back(first_value(v));
    out.insert(out.end(), src + v.src_first, src + v.src_first + v.src_count);
    if (j + 1 < streamline.size()) out.push_back(first_value(streamline[j + 1]));
    if (out.size() - at != used) throw std::logic_error("stage_values: a voxline's values and vertices differ");
  }
}

// Appends the voxlines of the streamline of `points` source points from `first_point` to `out`, as pass 2 found
// them: voxel runs from `run` on, which it advances past them.
void StreamingConversion::cut_by_runs(std::uint64_t first_point, std::uint64_t points, std::uint64_t& run,
                                      std::vector<TempVoxline>& out) const {
  const std::uint64_t end = first_point + points;
  for (std::uint64_t at = first_point; at < end;) {
    if (run >= table_.runs.size()) fail_changed();
    const VoxelRun v = table_.runs[run++];
    if (v.voxel == VoxelRuns::kVoxelisedAgain || v.points == 0 || v.points > end - at) fail_changed();
    out.push_back({v.voxel, v.points, at, kNoSynthetic});
    at += v.points;
  }
}

// In streamline order: adds the voxlines of a part staged in the first range to the voxel index's lists.
void StreamingConversion::index_part(const StagedPart& part) {
  std::size_t entry = 0;  // the streamline's first in part.table_entries
  for (std::size_t k = 0; k < part.streamline_voxlines.size(); ++k) {
    const std::uint32_t voxlines = part.streamline_voxlines[k];
    if (!table_.index_lists->add_streamline(part.source_first + k, {part.table_entries.data() + entry, voxlines}))
      fail_changed();  // more voxlines in a voxel than pass 2 counted
    entry += voxlines;
  }
}

// In streamline order: copies the vertices a part staged for half `half` of the range (split at
// placing.split) to their blocks (each voxel's next place for the streamline's depth) and, for the first
// range's first half, writes the part's voxline and streamline table entries and keeps its streamlines' spans.
void StreamingConversion::place_part(RangePlacement& placing, const StagedPart& part, int half) {
  const VoxelRange& r = placing.range;
  const std::uint32_t levels = job_.settings.levels;
  if (placing.tables && half == 0) {
    for (std::size_t k = 0; k < part.streamline_voxlines.size(); ++k) {
      table_.spans[part.source_first + k] = part.spans[k];
      placing.table_appender->add_streamline(placing.voxline_index);
      placing.voxline_index += part.streamline_voxlines[k];
    }
    for (const VoxlineEntry& e : part.table_entries) placing.table_appender->add_voxline(e);
  }
  const std::uint64_t bytes = vertex_bytes(job_.settings.positions);
  const auto* from = packed() ? reinterpret_cast<const std::uint8_t*>(part.words[half].data())
                              : reinterpret_cast<const std::uint8_t*>(part.xyz[half].data());
  const float* values = part.values[half].data();
  for (const StagedVoxline& v : part.voxlines[half]) {
    const std::size_t block = std::size_t(v.voxel) * levels + v.depth;
    std::uint64_t& cursor = table_.cursor[block];
    if (cursor > placing.block_end[block] || v.count > placing.block_end[block] - cursor) fail_changed();
    const std::uint64_t at = cursor - r.vertex_first;
    if (!packed()) ends_.set(at + v.count - 1);
    placing.sink.put(block, at, from, v.count);
    from += v.count * bytes;
    for (std::span<float> array : vertex_value_arrays_) {
      std::copy_n(values, v.count, array.data() + cursor);
      values += v.count;
    }
    cursor += v.count;
  }
  if (half == 0) placing.streamlines += part.end - part.begin;
}

}  // namespace vxl::streaming
