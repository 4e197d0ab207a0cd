#include "converter/package/unpack_positions.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "converter/convert/position_packing.h"
#include "converter/convert/segment_orders.h"
#include "format/base/error.h"
#include "format/base/parallel.h"
#include "format/streamline_length.h"
#include "format/vxlz_draco.h"
#include "format/vxlz_layout.h"
#include "format/vxlz_quantize.h"

namespace vxl {
namespace {

constexpr std::uint64_t kNoStreamline = std::numeric_limits<std::uint64_t>::max();

// The chunks that hold the points the file gets (all of them, or a level's), refused where the package lacks some.
std::uint64_t chunks_needed(const VxlzFile& f, const UnpackStructure& s) {
  const std::uint64_t chunks = (s.shipped_points + f.pack().chunk_points - 1) / f.pack().chunk_points;
  if (chunks > f.chunks_present())
    fail_input(f.path(), std::nullopt,
               "the positions of the streamlines asked for need " + std::to_string(chunks) + " chunks; " +
                   std::to_string(f.chunks_present()) + " are there");
  return chunks;
}

// Chunk `chunk`'s points decoded (spec §7 step 4), in shipping order, a run at a time: visit(position, j, k, xyz, n)
// for the n points (3 floats each) of voxline j from its k-th own point on, whose streamline is at `position` in the
// shipping order. They are decoded into `run_xyz`, or with `keep` into their vertices' place there (3 floats a
// vertex, VERT's order). Refuses a point outside the quantisation grid, checked per point so that a damaged chunk
// cannot drive the prediction into overflow.
template <typename Visit>
void decode_chunk(const VxlzFile& f, const UnpackStructure& s, std::uint64_t chunk, std::vector<float>& run_xyz,
                  float* keep, Visit&& visit) {
  const Quantizer quantizer(f.pack());
  const ChunkBytes bytes = f.chunk(chunk);
  ResidualChunk residuals(bytes, f.pack().joint_bits, f.chunk_point_count(chunk), f.path());
  // The chunk's points that the file holds: all of them, or for a level alone, those before its end.
  const std::uint64_t start = chunk * f.pack().chunk_points;
  const std::uint64_t count = std::min(f.chunk_point_count(chunk), s.shipped_points - start);
  ShippedVoxlineCursor at(s.order, s.strm, s.voxlines, start);
  LinearPredictor predictor;
  predictor.reset();
  const std::uint64_t max_value = quantizer.max_value();
  for (std::uint64_t i = 0; i < count;) {
    const std::uint64_t j = at.voxline(), in_voxline = at.point_in_voxline(), position = at.shipped_position();
    const std::uint64_t run = std::min(at.own() - in_voxline, count - i);
    if (in_voxline == 0 && s.starts_streamline[j]) predictor.start_streamline();
    if (!keep && run_xyz.size() < 3 * run) run_xyz.resize(3 * run);
    float* const xyz = keep ? keep + 3 * (s.first_vertex(j) + in_voxline) : run_xyz.data();
    for (std::uint64_t r = 0; r < run; ++r) {
      std::int32_t residual[3];
      residuals.next(residual);
      std::array<std::int64_t, 3> q;
      for (int a = 0; a < 3; ++a) q[a] = predictor.predict(a) + residual[a];
      // One unsigned comparison per value also catches negatives.
      if (static_cast<std::uint64_t>(q[0]) > max_value || static_cast<std::uint64_t>(q[1]) > max_value ||
          static_cast<std::uint64_t>(q[2]) > max_value)
        fail_input(f.path(), bytes.symbols_offset,
                   "position chunk: point " + std::to_string(start + i + r) + " decodes outside the quantisation grid");
      for (int a = 0; a < 3; ++a) xyz[3 * r + a] = quantizer.dequantize(q[a], a);
      predictor.push(q);
    }
    visit(position, j, in_voxline, xyz, run);
    i += run;
    at.advance(run);
  }
}

// Each voxel's bounds, grown by the chunks' threads at once: a bound is written only where a point widens it (rare
// once a voxel has a few points), by compare-and-swap.
class SharedVoxelBounds {
 public:
  explicit SharedVoxelBounds(std::size_t voxels)
      : lo_(new std::atomic<float>[3 * voxels]), hi_(new std::atomic<float>[3 * voxels]) {
    for (std::size_t i = 0; i < 3 * voxels; ++i) lo_[i] = INFINITY, hi_[i] = -INFINITY;
  }
  // Widens voxel `voxel`'s bounds by n points (3 floats each): their own bounds first, then one update.
  void add(std::uint32_t voxel, const float* xyz, std::uint64_t n) {
    float lo[3] = {xyz[0], xyz[1], xyz[2]}, hi[3] = {xyz[0], xyz[1], xyz[2]};
    for (const float* p = xyz + 3; p != xyz + 3 * n; p += 3)
      for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], p[c]), hi[c] = std::max(hi[c], p[c]);
    for (int c = 0; c < 3; ++c) {
      std::atomic<float>& low = lo_[3 * std::size_t(voxel) + c];
      std::atomic<float>& high = hi_[3 * std::size_t(voxel) + c];
      for (float now = low.load(std::memory_order_relaxed); lo[c] < now;)
        if (low.compare_exchange_weak(now, lo[c], std::memory_order_relaxed)) break;
      for (float now = high.load(std::memory_order_relaxed); hi[c] > now;)
        if (high.compare_exchange_weak(now, hi[c], std::memory_order_relaxed)) break;
    }
  }
  // Into the voxel table, a zero bound as +0 whichever zero came first (as the converter stores them).
  void store(std::span<VoxelEntry> voxels) const {
    for (std::size_t i = 0; i < voxels.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        voxels[i].tight_min[c] = lo_[3 * i + c].load(std::memory_order_relaxed) + 0.0f;
        voxels[i].tight_max[c] = hi_[3 * i + c].load(std::memory_order_relaxed) + 0.0f;
      }
  }

 private:
  std::unique_ptr<std::atomic<float>[]> lo_, hi_;
};

// A streamline's points in one chunk, where the chunk's start or end cuts it: the steps between them there, in order,
// and the first and last of them, joined to its parts in the chunks beside it once every chunk is decoded.
struct LengthPart {
  std::uint64_t streamline = kNoStreamline;
  bool has_point = false;
  std::array<float, 3> first{}, last{};
  std::vector<double> steps;
};
// head: a streamline begun in an earlier chunk; tail: one begun in this chunk that goes on past it.
struct ChunkLengthParts {
  LengthPart head, tail;
};

// One chunk's walk for the lengths (stored_length_of of a streamline's points, a voxline's synthetic first point
// left out): a streamline whole in the chunk gets its length here, one the chunk cuts leaves its part.
class ChunkLengths {
 public:
  ChunkLengths(const UnpackStructure& s, std::uint64_t first_point, std::uint64_t end_point, std::span<float> lengths,
               ChunkLengthParts& parts)
      : s_(s), first_point_(first_point), end_point_(end_point), lengths_(lengths), parts_(parts) {}

  // The n points of voxline j from its k-th own point on.
  void run(std::uint64_t position, std::uint64_t j, std::uint64_t k, const float* xyz, std::uint64_t n) {
    if (position != position_) start(position);
    if (k == 0 && (s_.voxlines[j].count_flags & kVoxlineSyntheticFirst))  // a voxel face's point, not the source's
      xyz += 3, --n;
    if (n == 0) return;
    if (part_) {
      for (const float* p = xyz; p != xyz + 3 * n; p += 3) part_point(p);
      return;
    }
    length_ = has_last_ ? polyline_extend(length_, last_.data(), xyz, n) : polyline_extend(0, xyz, xyz + 3, n - 1);
    std::copy_n(xyz + 3 * (n - 1), 3, last_.begin());
    has_last_ = true;
  }
  void finish() {
    if (position_ != kNoStreamline && !part_) lengths_[s_.order.streamlines[position_]] = static_cast<float>(length_);
  }

 private:
  void part_point(const float* xyz) {
    if (has_last_) {
      part_->steps.push_back(polyline_step(last_.data(), xyz));
    } else {
      std::copy_n(xyz, 3, part_->first.begin());
      part_->has_point = true;
    }
    std::copy_n(xyz, 3, last_.begin());
    has_last_ = true;
    part_->last = last_;
  }
  void start(std::uint64_t position) {
    finish();
    position_ = position;
    length_ = 0;
    has_last_ = false;
    const bool cut_before = s_.order.first_point[position] < first_point_;
    const bool cut_after = s_.order.first_point[position + 1] > end_point_;
    part_ = cut_before ? &parts_.head : cut_after ? &parts_.tail : nullptr;
    if (part_) part_->streamline = s_.order.streamlines[position];
  }

  const UnpackStructure& s_;
  std::uint64_t first_point_, end_point_;
  std::span<float> lengths_;
  ChunkLengthParts& parts_;
  std::uint64_t position_ = kNoStreamline;
  LengthPart* part_ = nullptr;
  double length_ = 0;
  bool has_last_ = false;
  std::array<float, 3> last_{};
};

// The lengths of the streamlines the chunks cut: their parts summed in chunk order, the step across each cut included,
// so that the sum runs in polyline_length's order.
void join_cut_streamlines(std::span<const ChunkLengthParts> chunks, std::span<float> lengths) {
  std::uint64_t streamline = kNoStreamline;
  double length = 0;
  bool has_last = false;
  std::array<float, 3> last{};
  auto finish = [&] {
    if (streamline != kNoStreamline) lengths[streamline] = static_cast<float>(length);
  };
  for (const ChunkLengthParts& chunk : chunks)
    for (const LengthPart* part : {&chunk.head, &chunk.tail}) {
      if (part->streamline == kNoStreamline) continue;
      if (part->streamline != streamline) {
        finish();
        streamline = part->streamline, length = 0, has_last = false;
      }
      if (!part->has_point) continue;
      if (has_last) length += polyline_step(last.data(), part->first.data());
      for (const double step : part->steps) length += step;
      last = part->last;
      has_last = true;
    }
  finish();
}

// VERT's (voxel, depth) blocks, each written through a region writer of its own from its first vertex to its end.
class VertexBlocks {
 public:
  VertexBlocks(VxlStreamWriter& out, const UnpackStructure& s, std::uint64_t staging_bytes, const std::string& path)
      : levels_(s.level_count), path_(path) {
    blocks_.resize(s.voxels.size() * levels_);
    for (std::size_t g = 0; g < s.voxels.size(); ++g) {
      const VoxelEntry& v = s.voxels[g];
      const std::span<const LevelEntry> row = level_row(s.levels, g, levels_);
      for (std::uint32_t d = 0; d < levels_; ++d) {  // depth d: [first, end) of the voxel's vertices
        Block& b = blocks_[g * levels_ + d];
        b.next = v.vertex_first + depth_first_vertex(row, d);
        b.end = v.vertex_first + depth_end_vertex(v, row, d);
        if (b.end > b.next)
          b.writer = out.region_writer(VxlStreamWriter::kVert, 4 * b.next, 4 * (b.end - b.next), staging_bytes);
      }
    }
  }
  // Words for vertices [vertex, vertex + n) of voxel `voxel`: the next ones of one of its blocks.
  void put(std::uint32_t voxel, std::uint64_t vertex, const std::uint32_t* words, std::uint64_t n) {
    for (std::uint32_t d = 0; d < levels_; ++d) {
      Block& b = blocks_[std::size_t(voxel) * levels_ + d];
      if (b.next != vertex || !b.writer) continue;
      if (n > b.end - b.next) break;
      b.writer->append({reinterpret_cast<const std::uint8_t*>(words), static_cast<std::size_t>(4 * n)});
      b.next += n;
      if (b.next == b.end) b.writer.reset();  // written out: its staging goes
      return;
    }
    fail_input(path_, std::nullopt,
               "voxel " + std::to_string(voxel) + ": its vertices " + std::to_string(vertex) + ".." +
                   std::to_string(vertex + n - 1) + " do not come next in the package's points");
  }
  void check_complete() const {
    for (std::size_t k = 0; k < blocks_.size(); ++k)
      if (blocks_[k].writer)
        fail_input(path_, std::nullopt,
                   "voxel " + std::to_string(k / levels_) + " does not get all of its vertices from the package");
  }

 private:
  struct Block {
    std::uint64_t next = 0, end = 0;  // vertices
    std::unique_ptr<DirectRegionWriter> writer;
  };
  std::uint32_t levels_;
  std::string path_;
  std::vector<Block> blocks_;  // voxel-major
};

// The largest packing error bound of the voxels, their tight bounds set.
double largest_packing_bound(std::span<const VoxelEntry> voxels) {
  double bound = 0;
  for (const VoxelEntry& v : voxels) bound = std::max(bound, packed_error_bound(v));
  return bound;
}

}  // namespace

double write_positions_in_blocks(const VxlzFile& f, const UnpackStructure& s, const VoxlineEnds& ends,
                                 VxlStreamWriter& out, std::uint64_t staging_bytes,
                                 const std::function<void(double)>& progress) {
  const std::uint64_t chunks = chunks_needed(f, s);
  std::vector<VertexPacker> packers;
  packers.reserve(s.voxels.size());
  for (const VoxelEntry& v : s.voxels) packers.emplace_back(v);
  VertexBlocks blocks(out, s, staging_bytes, f.path());
  std::vector<std::uint32_t> words;
  // n vertices of voxel `voxel` from `vertex` on (3 floats each).
  const auto write = [&](std::uint32_t voxel, std::uint64_t vertex, const float* xyz, std::uint64_t n) {
    if (words.size() < n) words.resize(n);
    packers[voxel].words(xyz, n, words.data());
    for (std::uint64_t i = 0; i < n; ++i)
      if (ends.test(vertex + i)) words[i] |= kPackedVoxlineEnd;
    blocks.put(voxel, vertex, words.data(), n);
  };
  std::vector<float> run_xyz;
  for (std::uint64_t chunk = 0; chunk < chunks; ++chunk) {
    decode_chunk(f, s, chunk, run_xyz, nullptr,
                 [&](std::uint64_t, std::uint64_t j, std::uint64_t k, const float* xyz, std::uint64_t n) {
                   if (k == 0 && !s.starts_streamline[j])  // the connecting vertex that ends the voxline before
                     write(s.voxlines[j - 1].voxel, s.first_vertex(j - 1) + s.own(j - 1), xyz, 1);
                   write(s.voxlines[j].voxel, s.first_vertex(j) + k, xyz, n);
                 });
    if (progress) progress(double(chunk + 1) / double(chunks));
  }
  blocks.check_complete();
  return largest_packing_bound(s.voxels);
}

std::uint64_t open_block_staging_bytes(const UnpackStructure& s, const PackSection& pack, std::uint64_t staging_bytes) {
  const std::uint32_t levels = s.level_count;
  // The shipped depth whose points fill output depth d: in level order the coarsest shipped depth also fills the
  // output's coarser ones; in streamline order every depth fills at once (one group).
  const bool level_order = pack.predictor == kVxlzPredictorLinearLevelOrder;
  const auto group_of = [&](std::uint32_t d) { return level_order ? std::min(d, pack.level_count - 1) : 0u; };
  std::vector<std::uint64_t> open(levels, 0);  // per group
  for (std::size_t g = 0; g < s.voxels.size(); ++g) {
    const VoxelEntry& v = s.voxels[g];
    const std::span<const LevelEntry> row = level_row(s.levels, g, levels);
    for (std::uint32_t d = 0; d < levels; ++d)
      if (const std::uint64_t n = depth_end_vertex(v, row, d) - depth_first_vertex(row, d); n > 0)
        open[group_of(d)] += DirectRegionWriter::staging_size(4 * n, staging_bytes);
  }
  return *std::max_element(open.begin(), open.end());
}

void scan_positions(const VxlzFile& f, UnpackStructure& s, VoxlineEnds& ends, std::span<float> lengths,
                    unsigned threads, const std::function<void(double)>& progress, float* keep) {
  const std::uint64_t chunks = chunks_needed(f, s);
  SharedVoxelBounds bounds(s.voxels.size());
  std::vector<ChunkLengthParts> parts(chunks);
  std::vector<std::vector<float>> run_xyz(resolve_threads(threads));  // per thread: a voxline's decoded run
  std::atomic<std::uint64_t> done{0};
  parallel_for(chunks, threads, [&](std::uint64_t chunk, unsigned t) {
    const std::uint64_t first = chunk * f.pack().chunk_points;
    ChunkLengths chunk_lengths(s, first, std::min(first + f.chunk_point_count(chunk), s.shipped_points), lengths,
                               parts[chunk]);
    decode_chunk(f, s, chunk, run_xyz[t], keep,
                 [&](std::uint64_t position, std::uint64_t j, std::uint64_t k, const float* xyz, std::uint64_t n) {
                   bounds.add(s.voxlines[j].voxel, xyz, n);
                   // A voxline's first point is also the connecting vertex that ends the voxline before it in its
                   // streamline.
                   if (k == 0 && !s.starts_streamline[j]) {
                     bounds.add(s.voxlines[j - 1].voxel, xyz, 1);
                     if (keep) std::memcpy(keep + 3 * (s.first_vertex(j - 1) + s.own(j - 1)), xyz, 12);
                   }
                   if (k + n == s.own(j)) ends.set(s.first_vertex(j) + s.own(j) + s.connected(j) - 1);
                   chunk_lengths.run(position, j, k, xyz, n);
                 });
    chunk_lengths.finish();
    const std::uint64_t d = ++done;
    if (t == 0 && progress) progress(double(d) / double(chunks));
  });
  join_cut_streamlines(parts, lengths);
  bounds.store(s.voxels);
  // Every voxel gets a point where the voxlines' points are the package's (rebuild_structure checks them): a voxel
  // without one would keep inverted bounds, which no check after this one would see.
  for (std::size_t i = 0; i < s.voxels.size(); ++i)
    if (!(s.voxels[i].tight_min[0] <= s.voxels[i].tight_max[0]))
      fail_input(f.path(), std::nullopt, "voxel " + std::to_string(i) + " gets no decoded point");
}

double pack_kept_positions(const UnpackStructure& s, std::span<float> kept, const VoxlineEnds& ends,
                           std::span<std::uint32_t> words, unsigned threads) {
  pack_vertex_blocks(s.voxels, kept, ends, words, threads);
  return largest_packing_bound(s.voxels);
}

double write_positions(const VxlzFile& f, const UnpackStructure& s, const VoxlineEnds& ends,
                       std::span<std::uint32_t> words, unsigned threads, const std::function<void(double)>& progress) {
  const std::uint64_t chunks = chunks_needed(f, s);
  std::vector<VertexPacker> packers;
  packers.reserve(s.voxels.size());
  for (const VoxelEntry& v : s.voxels) packers.emplace_back(v);
  // n vertices of voxel `voxel` from `vertex` on (3 floats each).
  const auto write = [&](std::uint32_t voxel, std::uint64_t vertex, const float* xyz, std::uint64_t n) {
    packers[voxel].words(xyz, n, words.data() + vertex);
    for (std::uint64_t i = vertex; i < vertex + n; ++i)
      if (ends.test(i)) words[i] |= kPackedVoxlineEnd;
  };
  std::vector<std::vector<float>> run_xyz(resolve_threads(threads));
  std::atomic<std::uint64_t> done{0};
  parallel_for(chunks, threads, [&](std::uint64_t chunk, unsigned t) {
    decode_chunk(f, s, chunk, run_xyz[t], nullptr,
                 [&](std::uint64_t, std::uint64_t j, std::uint64_t k, const float* xyz, std::uint64_t n) {
                   write(s.voxlines[j].voxel, s.first_vertex(j) + k, xyz, n);
                   if (k == 0 && !s.starts_streamline[j])  // the connecting vertex before it: a copy, bit for bit
                     write(s.voxlines[j - 1].voxel, s.first_vertex(j - 1) + s.own(j - 1), xyz, 1);
                 });
    const std::uint64_t d = ++done;
    if (t == 0 && progress) progress(double(d) / double(chunks));
  });
  return largest_packing_bound(s.voxels);
}

}  // namespace vxl
