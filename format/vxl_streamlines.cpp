#include "format/vxl_streamlines.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <exception>
#include <memory>
#include <vector>

#include "format/base/batch_queue.h"
#include "format/base/error.h"

namespace vxl {

namespace {

// A voxline as the table walk placed it (spec §5.6): where its vertices start and what it is to its streamline.
struct WalkedVoxline {
  std::uint64_t first_vertex;
  std::uint32_t voxel;
  std::uint32_t own_points;
  bool synthetic_first;
  bool first_of_streamline;
  bool connected;
};

// A run of streamlines: walked through the table by the queue's read, their points decoded by its parts, handed
// to the callbacks by its sink. Cache-line aligned: the read fills one batch while the parts, on another core,
// read the other.
struct alignas(64) WalkBatch {
  std::uint64_t first_streamline = 0;
  std::vector<WalkedVoxline> voxlines;       // those the parts or the sink use, in table order
  std::vector<std::uint64_t> voxline_start;  // per streamline (and one past): its first entry in `voxlines`
  std::vector<std::uint64_t> point_start;    // per streamline (and one past): its first float in `points`
  std::vector<std::uint8_t> read;            // per streamline: its points are decoded
  std::vector<std::uint64_t> part_start;     // per part (and one past): its first streamline in the batch
  // The read streamlines' source points, x,y,z interleaved (not zeroed first: every float is decoded into).
  std::unique_ptr<float[]> points;
  std::uint64_t points_capacity = 0;
  std::uint64_t size() const { return read.size(); }
};

// Per batch: about this many decoded points (6 MB of floats; four batches are held), as many voxlines kept, and
// at most this many streamlines (a walk that reads few keeps its tables small). Parts of a batch: enough that
// the threads finish a round together.
constexpr std::uint64_t kBatchPoints = 1u << 19;
constexpr std::uint64_t kBatchVoxlines = 1u << 19;
constexpr std::uint64_t kBatchStreamlines = 1u << 16;
constexpr std::uint64_t kPartsPerThread = 4;
// The mapped pages read are let go every so often: a walk through a whole file (export, a large selection)
// otherwise keeps every page it touched resident (the 1M set's blocks and tables: 365 MB).
constexpr std::uint64_t kReleaseEvery = 64ull << 20;

// The walk as a run_batch_queue pass: the table walked in order (every check that needs no vertex), the points
// decoded side by side, the callbacks called in order.
class StreamlineWalk {
 public:
  StreamlineWalk(const VxlFile& f, const WalkCallbacks& cb)
      : f_(f),
        cb_(cb),
        path_(f.path()),
        levels_(f.level_count()),
        packed_(f.position_encoding() == PositionEncoding::Packed),
        vxln_at_(f.find_section(section_id("VXLN"))->offset),
        strm_(f.streamline_first_voxline()),
        voxlines_(f.voxlines()) {
    f.check_streamline_table();
    // One cursor per voxel and depth: a voxel's block holds the voxlines of deeper streamlines first (spec
    // §5.4, §5.12), each depth's in streamline order. Each cursor's end is kept beside it: one cache line
    // read per voxline walked.
    const auto voxels = f.voxels();
    cursors_.resize(voxels.size() * levels_);
    for (std::size_t i = 0; i < voxels.size(); ++i)
      for (std::uint32_t d = 0; d < levels_; ++d) {
        cursors_[i * levels_ + d] = {voxels[i].vertex_first + depth_first_vertex(f.levels_of(i), d),
                                     voxels[i].vertex_first + depth_end_vertex(voxels[i], f.levels_of(i), d)};
      }
    if (packed_)
      for (const VoxelEntry& v : voxels) {
        error_bound_.push_back(packed_error_bound(v));
        packers_.emplace_back(v);
      }
  }

  void run() {
    const unsigned threads = resolve_threads(cb_.threads);
    parts_ = threads > 1 ? threads * kPartsPerThread : 1;
    BatchQueueShape shape;
    shape.parts = parts_;
    shape.sink_items = 1;
    shape.read_ahead = threads > 1;
    run_batch_queue(
        threads, shape, [&](int slot) { return read_batch(slot); }, [&](int slot) { prepare(slot); },
        [&](int slot, std::uint64_t part, unsigned) { decode_part(slot, part); },
        [&](int slot, std::uint64_t, unsigned) { hand_on(slot); },
        // The sink runs beside the next read into the same slot: a batch whose parts are done moves aside.
        [&](int slot) { std::swap(batches_[slot], made_[slot]); });
    check_totals();
  }

 private:
  // The next batch of streamlines walked through the table. A streamline that fails ends the batch before it,
  // and its error comes at the next read: the streamlines before it are decoded first, and their own faults
  // reported first, as a walk one streamline at a time would.
  bool read_batch(int slot) {
    if (walked_.pending_error) std::rethrow_exception(std::exchange(walked_.pending_error, nullptr));
    const std::uint64_t count = strm_.size() - 1;
    if (walked_.next_streamline == count) return false;
    if (walked_.read_since_release > kReleaseEvery) {
      f_.release_resident_pages();
      walked_.read_since_release = 0;
    }
    WalkBatch& b = batches_[slot];
    b.first_streamline = walked_.next_streamline;
    b.voxlines.clear();
    b.read.clear();
    b.voxline_start.assign(1, 0);
    b.point_start.assign(1, 0);
    std::uint64_t points_read = 0;
    while (walked_.next_streamline < count && points_read < kBatchPoints && b.voxlines.size() < kBatchVoxlines &&
           b.size() < kBatchStreamlines) {
      try {
        points_read += walk_streamline(walked_.next_streamline, b);
      } catch (...) {
        if (b.size() == 0) throw;
        walked_.pending_error = std::current_exception();
        b.voxlines.resize(b.voxline_start.back());
        break;
      }
      ++walked_.next_streamline;
    }
    return true;
  }

  // Streamline s's voxlines placed by the cursors and checked; returns the points it adds to the batch.
  std::uint64_t walk_streamline(std::uint64_t s, WalkBatch& b) {
    const std::uint64_t first = strm_[s], last = strm_[s + 1];
    const std::uint32_t depth = streamline_depth(s, levels_);
    const bool read = !cb_.read_points || cb_.read_points(s);
    const bool keep = read || cb_.voxline;
    const std::uint64_t vertex_bytes = read ? (packed_ ? 4 : 12) : 0;
    std::uint64_t points = 0, synthetic = 0, bytes = 0;
    for (std::uint64_t j = first; j < last; ++j) {
      f_.check_voxline(j);
      const VoxlineEntry& e = voxlines_[j];
      const std::uint32_t own = e.count_flags & kVoxlineCountMask;
      const bool synthetic_first = (e.count_flags & kVoxlineSyntheticFirst) != 0;
      const bool connected = j + 1 < last;
      if (synthetic_first && j == first)
        fail_input(path_, vxln_at_ + 8 * j, "a streamline cannot start with a synthetic point");
      Cursor& cursor = cursors_[e.voxel * levels_ + depth];
      std::uint64_t& here = cursor.here;
      const std::uint64_t end = cursor.end;
      const std::uint64_t need = std::uint64_t(own) + (connected ? 1 : 0);
      if (here > end || need > end - here)
        fail_input(path_, vxln_at_ + 8 * j, "voxline runs past its voxel's vertex block (or its level's part of it)");
      synthetic += synthetic_first ? 1 : 0;
      points += own - (synthetic_first ? 1 : 0);
      bytes += sizeof(VoxlineEntry) + need * vertex_bytes;
      if (keep) b.voxlines.push_back({here, e.voxel, own, synthetic_first, j == first, connected});
      here += need;
    }
    walked_.total_points += points;
    walked_.synthetic += synthetic;
    walked_.read_since_release += bytes;
    b.read.push_back(read ? 1 : 0);
    b.voxline_start.push_back(b.voxlines.size());
    b.point_start.push_back(b.point_start.back() + (read ? 3 * points : 0));
    return read ? points : 0;
  }

  // Before the parts: room for the points, and the batch cut into parts of about equal points.
  void prepare(int slot) {
    WalkBatch& b = batches_[slot];
    const std::uint64_t floats = b.point_start.back();
    if (floats > b.points_capacity) {
      b.points = std::unique_ptr<float[]>(new float[floats]);
      b.points_capacity = floats;
    }
    b.part_start.assign(1, 0);
    for (std::uint64_t k = 1; k < parts_; ++k) {
      const auto from = b.point_start.begin() + static_cast<std::ptrdiff_t>(b.part_start.back());
      const auto cut = std::lower_bound(from, b.point_start.end() - 1, floats * k / parts_);
      b.part_start.push_back(static_cast<std::uint64_t>(cut - b.point_start.begin()));
    }
    b.part_start.push_back(b.size());
  }

  // A part's read streamlines decoded straight into the batch's points, the synthetic first points and the
  // connecting vertices left out. A connecting vertex and the next voxline's first point are one source point,
  // stored in two voxels' blocks: equal bit for bit as float32, within both voxels' error bounds when packed
  // (spec §5.4).
  void decode_part(int slot, std::uint64_t part) const {
    const WalkBatch& b = batches_[slot];
    for (std::uint64_t i = b.part_start[part]; i < b.part_start[part + 1]; ++i) {
      if (!b.read[i]) continue;
      float* out = b.points.get() + b.point_start[i];
      float connector[3];  // the previous voxline's connecting vertex (each voxline but the last has one)
      for (std::uint64_t k = b.voxline_start[i]; k < b.voxline_start[i + 1]; ++k) {
        const WalkedVoxline& v = b.voxlines[k];
        if (!v.first_of_streamline) {
          float first[3];
          decode_vertex(v, 0, first);
          if (!same_point(connector, b.voxlines[k - 1].voxel, first, v.voxel))
            fail_input(path_, vxln_at_ + 8 * (strm_[b.first_streamline + i] + (k - b.voxline_start[i])),
                       "connecting vertex differs from the next voxline's first point");
        }
        const std::uint32_t skip = v.synthetic_first ? 1 : 0, points = v.own_points - skip;
        if (packed_)
          packers_[v.voxel].decode(f_.packed_vertices().data() + v.first_vertex + skip, points, out);
        else
          std::copy_n(f_.float_vertices().data() + 3 * (v.first_vertex + skip), 3 * points, out);
        out += 3 * points;
        if (v.connected) decode_vertex(v, v.own_points, connector);
      }
    }
  }

  void decode_vertex(const WalkedVoxline& v, std::uint64_t k, float* xyz) const {
    if (packed_)
      packers_[v.voxel].decode_word(f_.packed_vertices()[v.first_vertex + k], xyz);
    else
      std::copy_n(f_.float_vertices().data() + 3 * (v.first_vertex + k), 3, xyz);
  }

  bool same_point(const float* a, std::uint32_t voxel_a, const float* b, std::uint32_t voxel_b) const {
    if (!packed_) return std::memcmp(a, b, 12) == 0;
    const double tolerance = error_bound_[voxel_a] + error_bound_[voxel_b];
    for (int c = 0; c < 3; ++c)
      if (!(std::abs(double(a[c]) - double(b[c])) <= tolerance)) return false;
    return true;
  }

  // The callbacks, in table order, one at a time.
  void hand_on(int slot) const {
    const WalkBatch& b = made_[slot];
    for (std::uint64_t i = 0; i < b.size(); ++i) {
      const std::uint64_t s = b.first_streamline + i;
      if (cb_.voxline)
        for (std::uint64_t k = b.voxline_start[i]; k < b.voxline_start[i + 1]; ++k) {
          const WalkedVoxline& v = b.voxlines[k];
          cb_.voxline(
              {s, v.voxel, v.first_vertex, v.own_points, v.synthetic_first, v.first_of_streamline, v.connected});
        }
      if (b.read[i] && cb_.streamline)
        cb_.streamline(
            s, std::span<const float>(b.points.get() + b.point_start[i], b.point_start[i + 1] - b.point_start[i]));
    }
  }

  // After the last streamline: every block consumed exactly, the totals META states.
  void check_totals() const {
    const std::uint64_t voxels = f_.voxels().size();
    for (std::size_t i = 0; i < voxels; ++i)
      for (std::uint32_t d = 0; d < levels_; ++d)
        if (cursors_[i * levels_ + d].here != cursors_[i * levels_ + d].end)
          fail_input(path_, f_.find_section(section_id("VOXT"))->offset + 64 * i,
                     "voxel block has vertices no voxline uses" +
                         (levels_ > 1 ? " (at depth " + std::to_string(d) + ")" : std::string()));
    const MetaSection& m = f_.meta();
    if (walked_.total_points != m.point_count)
      fail_input(path_, std::nullopt,
                 "streamlines hold " + std::to_string(walked_.total_points) + " points but META says " +
                     std::to_string(m.point_count));
    if (walked_.synthetic != m.synthetic_point_count)
      fail_input(path_, std::nullopt, "synthetic point count does not match META");
  }

  const VxlFile& f_;
  const WalkCallbacks& cb_;
  const std::string& path_;
  const std::uint32_t levels_;
  const bool packed_;
  const std::uint64_t vxln_at_;
  const std::span<const std::uint64_t> strm_;
  const std::span<const VoxlineEntry> voxlines_;
  struct Cursor {
    std::uint64_t here, end;  // the next vertex of the voxel's depth, and one past its last
  };
  std::vector<Cursor> cursors_;
  std::vector<double> error_bound_;    // per voxel, packed
  std::vector<VertexPacker> packers_;  // per voxel, packed: made once, not once per voxline read
  std::uint64_t parts_ = 1;
  // Per slot, the batch being read and decoded, and the one made (its parts done) that the sink hands on.
  std::array<WalkBatch, 2> batches_, made_;
  // What the read changes as it goes, on a cache line of its own.
  struct alignas(64) {
    std::uint64_t total_points = 0, synthetic = 0, read_since_release = 0, next_streamline = 0;
    std::exception_ptr pending_error;
  } walked_;
};

}  // namespace

void walk_streamlines(const VxlFile& f, const WalkCallbacks& cb) { StreamlineWalk(f, cb).run(); }

}  // namespace vxl
