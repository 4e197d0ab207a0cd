#include "converter/convert/segment_orders.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "converter/convert/segment_sort.h"
#include "format/base/error.h"
#include "format/base/parallel.h"
#include "format/vxl_positions.h"

namespace vxl {

OrderSetSpec parse_order_set(const std::string& name) {
  OrderSetSpec set;
  set.name = name;
  set.directions = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  if (name == "axis") {
    set.kind = OrderSet::Axis;
    return set;
  }
  if (name == "axis+diag") {
    set.kind = OrderSet::AxisDiag;
    const float k = static_cast<float>(1.0 / std::sqrt(3.0));
    // One of each ± pair of cube diagonals; the reversed orders give the other four.
    set.directions.push_back({k, k, k});
    set.directions.push_back({-k, k, k});
    set.directions.push_back({k, -k, k});
    set.directions.push_back({k, k, -k});
    return set;
  }
  if (name.starts_with("random:")) {
    const std::string count = name.substr(7);
    const bool digits =
        !count.empty() && count.size() <= 2 && count.find_first_not_of("0123456789") == std::string::npos;
    const unsigned n = digits ? static_cast<unsigned>(std::stoul(count)) : 0;
    if (n >= 1 && n <= kVxlMaxStoredOrders) {
      set.kind = OrderSet::Random;
      set.directions.assign(n, {1, 0, 0});  // placeholders: the real directions are per voxel
      return set;
    }
  }
  throw Error(ErrorKind::Usage, "", std::nullopt,
              "unknown order set '" + name + "' (expected axis, axis+diag or random:N with N in 1..64)");
}

namespace {

// splitmix64 (Steele, Lea & Flood, "Fast splittable pseudorandom number generators", 2014): our own, so
// that the directions do not depend on the standard library.
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform_signed() { return double(next() >> 11) * 0x1.0p-52 - 1.0; }  // [-1, 1), exactly
};

// A generator whose stream depends on (seed, coord) alone: each coordinate is folded in through a full
// splitmix64 step, so neighbouring voxels get unrelated directions.
SplitMix64 voxel_generator(std::uint64_t seed, const std::int32_t (&coord)[3]) {
  SplitMix64 g{seed};
  for (int c = 0; c < 3; ++c) {
    g.state ^= std::uint64_t(std::uint32_t(coord[c])) << (16 * c);
    g.state = g.next();
  }
  return g;
}

// A direction uniform on the unit sphere: a point uniform in the unit ball (rejection from the cube),
// normalised. Only + * / sqrt: the same bits on every IEEE-754 platform, unlike sin/cos.
std::array<float, 3> uniform_direction(SplitMix64& g) {
  for (;;) {
    const double x = g.uniform_signed(), y = g.uniform_signed(), z = g.uniform_signed();
    const double r2 = x * x + y * y + z * z;
    if (r2 > 1.0 || r2 < 1e-6) continue;  // outside the ball, or too short to normalise accurately
    const double inv = 1.0 / std::sqrt(r2);
    return {static_cast<float>(x * inv), static_cast<float>(y * inv), static_cast<float>(z * inv)};
  }
}

}  // namespace

std::vector<DirectionEntry> order_directions(const OrderSetSpec& set) {
  std::vector<DirectionEntry> out;
  for (const auto& d : set.directions) out.push_back({{d[0], d[1], d[2]}, 0});
  return out;
}

void voxel_directions(const OrderSetSpec& set, const std::int32_t (&coord)[3], std::span<std::array<float, 3>> out) {
  if (!set.per_voxel()) {
    std::copy(set.directions.begin(), set.directions.end(), out.begin());
    return;
  }
  SplitMix64 g = voxel_generator(set.seed, coord);
  for (auto& d : out) d = uniform_direction(g);
}

void fill_voxel_directions(const OrderSetSpec& set, std::span<const VoxelEntry> voxels, std::span<DirectionEntry> out) {
  if (!set.per_voxel()) return;
  const std::size_t k_count = set.directions.size();
  std::vector<std::array<float, 3>> dirs(k_count);
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    voxel_directions(set, voxels[i].coord, dirs);
    for (std::size_t k = 0; k < k_count; ++k) out[i * k_count + k] = {{dirs[k][0], dirs[k][1], dirs[k][2]}, 0};
  }
}

std::uint64_t layout_orders(std::span<VoxelEntry> voxels, std::span<const LevelEntry> levels, std::uint32_t level_count,
                            std::uint32_t stored_orders) {
  if (levels.size() != voxels.size() * (level_count - 1))
    throw std::logic_error("layout_orders: not level_count - 1 level entries per voxel");
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    VoxelEntry& v = voxels[i];
    v.flags = order_width_code(v.vertex_count);
    v.order_offset = total;
    total += voxel_all_orders_size(v, level_row(levels, i, level_count), stored_orders, OrderPacking::Bits);
  }
  return total;
}

// A voxel's block as packed words: a coordinate is looked up in a table of what each of the 1024
// quanta of its axis decodes to (VertexPacker::decode_axis), so the block is never decoded whole.
struct PackedBlock {
  const std::uint32_t* words;
  std::array<std::array<float, kPackedSteps + 1>, 3> decoded;
  std::array<detail::QuantumSumKeys, 3> sums;  // by axis
  float axis(std::uint32_t e, int c) const { return decoded[c][(words[e] >> (10 * c)) & kPackedAxisMask]; }
  bool ends_voxline(std::uint32_t e) const { return (words[e] & kPackedVoxlineEnd) != 0; }
};

// A small voxel's packed words decoded whole: fewer operations than the three tables, and no larger.
struct DecodedPackedBlock {
  const std::uint32_t* words;
  const float* xyz;
  float axis(std::uint32_t e, int c) const { return xyz[3 * std::size_t(e) + c]; }
  bool ends_voxline(std::uint32_t e) const { return (words[e] & kPackedVoxlineEnd) != 0; }
};
constexpr std::uint32_t kDecodedWholeVertices = kPackedSteps + 1;  // 3 floats each: the tables' size

struct VoxelOrderWriter::Scratch {
  std::vector<std::uint32_t> starts;
  detail::SortScratch sort;
  PackedBlock packed;          // write_packed's tables, 85 KiB: here rather than on the stack or per voxel
  std::vector<float> decoded;  // a small voxel's positions
};

VoxelOrderWriter::VoxelOrderWriter(const OrderSetSpec& set, std::uint32_t max_vertices)
    : set_(&set),
      directions_(set.directions.size()),
      axis_of_(set.directions.size(), -1),
      scratch_(std::make_unique<Scratch>()) {
  detail::SortScratch& s = scratch_->sort;
  s.max_vertices = max_vertices;
  for (auto* v : {&s.keys, &s.packed_tmp}) v->reserve(max_vertices);
  scratch_->starts.reserve(max_vertices);
}

void VoxelOrderWriter::use_directions_of(const VoxelEntry& v) {
  if (have_directions_ && !set_->per_voxel()) return;
  voxel_directions(*set_, v.coord, directions_);
  // Axis directions sort by one exact component sum, as in the paper; others by a dot product.
  for (std::size_t k = 0; k < directions_.size(); ++k) {
    axis_of_[k] = -1;
    for (int c = 0; c < 3; ++c)
      if (directions_[k][c] == 1.0f && directions_[k][(c + 1) % 3] == 0.0f && directions_[k][(c + 2) % 3] == 0.0f)
        axis_of_[k] = c;
  }
  have_directions_ = true;
}

VoxelOrderWriter::~VoxelOrderWriter() = default;
VoxelOrderWriter::VoxelOrderWriter(VoxelOrderWriter&&) noexcept = default;

// A voxel's block as float32 positions, and its voxline ends.
struct FloatBlock {
  const float* xyz;
  const VoxlineEnds& ends;
  std::uint64_t first;  // the block's first vertex in `ends`
  float axis(std::uint32_t e, int c) const { return xyz[3 * std::size_t(e) + c]; }
  bool ends_voxline(std::uint32_t e) const { return ends.test(first + e); }
};

void VoxelOrderWriter::write(const VoxelEntry& v, std::span<const LevelEntry> row, std::span<const float> vertices,
                             const VoxlineEnds& ends, std::uint8_t* dst) {
  write_levels(v, row, FloatBlock{vertices.data() + 3 * v.vertex_first, ends, v.vertex_first}, dst);
}

void VoxelOrderWriter::write_packed(const VoxelEntry& v, std::span<const LevelEntry> row, const std::uint32_t* words,
                                    std::uint8_t* dst) {
  const VertexPacker packer(v);
  if (v.vertex_count <= kDecodedWholeVertices) {
    std::vector<float>& xyz = scratch_->decoded;
    xyz.resize(3 * std::size_t(v.vertex_count));
    packer.decode(words, v.vertex_count, xyz.data());
    write_levels(v, row, DecodedPackedBlock{words, xyz.data()}, dst);
    return;
  }
  PackedBlock& block = scratch_->packed;
  block.words = words;
  // The quantum sums' tables (some 7k operations an axis) pay only where the sorts are long, and only along
  // the axes a shared set sorts by (a per-voxel set's random directions are no axes).
  constexpr std::uint32_t kRankedVoxelVertices = 1u << 14;
  const bool ranked = !set_->per_voxel() && v.vertex_count >= kRankedVoxelVertices;
  for (int c = 0; c < 3; ++c) {
    packer.decode_axis_table(c, block.decoded[c]);
    const bool along_c = std::any_of(set_->directions.begin(), set_->directions.end(), [&](const auto& d) {
      return d[c] == 1.0f && d[(c + 1) % 3] == 0.0f && d[(c + 2) % 3] == 0.0f;
    });
    if (ranked && along_c)
      block.sums[c].prepare(block.decoded[c]);
    else
      block.sums[c].clear();
  }
  write_levels(v, row, block, dst);
}

template <typename Block>
void VoxelOrderWriter::write_levels(const VoxelEntry& v, std::span<const LevelEntry> row, const Block& block,
                                    std::uint8_t* dst) {
  use_directions_of(v);
  const std::uint32_t k = static_cast<std::uint32_t>(directions_.size());
  for (std::uint32_t level = 0; level <= row.size(); ++level) {
    const LevelEntry counts = voxel_level(v, row, level);
    std::uint8_t* const level_end = dst + level_orders_size(counts, k, OrderPacking::Bits);
    if (counts.segment_count > 0) dst = write_level(counts, block, dst);
    std::fill(dst, level_end, std::uint8_t{0});  // the padding to 4 bytes
    dst = level_end;
  }
}

template <typename Block>
std::uint8_t* VoxelOrderWriter::write_level(const LevelEntry& level, const Block& block, std::uint8_t* dst) {
  std::vector<std::uint32_t>& starts = scratch_->starts;
  detail::SortScratch& scratch = scratch_->sort;
  // The segments start at every vertex that does not end its voxline (branch-free: ends are
  // scattered, a branch would mispredict often).
  starts.resize(level.vertex_count);
  std::size_t n_starts = 0;
  for (std::uint32_t e = 0; e < level.vertex_count; ++e) {
    starts[n_starts] = e;
    n_starts += !block.ends_voxline(e);
  }
  starts.resize(n_starts);
  if (n_starts != level.segment_count) throw std::logic_error("VoxelOrderWriter: level segment count mismatch");
  const std::uint32_t bits = order_entry_bits(level.vertex_count, OrderPacking::Bits);
  for (std::size_t k = 0; k < directions_.size(); ++k) {
    const int axis = axis_of_[k];
    if constexpr (std::is_same_v<Block, PackedBlock>) {
      if (axis >= 0 && starts.size() >= 2) {
        if (std::uint8_t* end =
                block.sums[axis].sort(starts, block.words, axis, level.vertex_count, bits, scratch, dst)) {
          dst = end;
          continue;
        }
      }
    }
    scratch.keys.resize(starts.size());
    const auto& d = directions_[k];
    std::uint64_t all_or = 0, all_and = ~0ull;
    for (std::size_t n = 0; n < starts.size(); ++n) {
      const std::uint32_t a = starts[n];  // the segment (a, a + 1)
      double key;
      if (axis >= 0) {
        key = double(block.axis(a, axis)) + double(block.axis(a + 1, axis));
      } else {
        key = 0;
        for (int c = 0; c < 3; ++c) key += (double(block.axis(a, c)) + double(block.axis(a + 1, c))) * double(d[c]);
      }
      const std::uint64_t bits = detail::sortable_bits(key);
      scratch.keys[n] = bits;
      all_or |= bits;
      all_and &= bits;
    }
    dst = detail::sort_segments(starts, level.vertex_count, bits, all_or ^ all_and, scratch, dst);
  }
  return dst;
}

std::uint64_t order_scratch_bytes(std::uint32_t max_vertices) {
  return sizeof(std::uint32_t) * std::uint64_t(max_vertices) + detail::sort_scratch_bytes(max_vertices);  // + starts
}

}  // namespace vxl
