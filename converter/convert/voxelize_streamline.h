// The per-streamline core of voxelisation (Algorithm 1 of the Voxlines paper, with the splitting of long
// steps at voxel faces, spec §6.3), shared by voxelize.cpp (whole tractogram in memory) and
// streaming_convert.cpp (bounded memory), so that both make exactly the same voxlines. Internal: the
// public interface is voxelize.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <vector>

#include "format/vxl_layout.h"

namespace vxl::detail {

constexpr std::uint64_t kNoSynthetic = std::numeric_limits<std::uint64_t>::max();

struct Coord {
  std::int32_t x, y, z;
  bool operator==(const Coord&) const = default;
};
inline bool zyx_less(const Coord& a, const Coord& b) {
  if (a.z != b.z) return a.z < b.z;
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

// Open-addressing hash map from voxel coordinate to a dense local id. Only consulted when a streamline
// changes voxel (about one point in seven at 10 mm), so simplicity beats cleverness here.
class VoxelIndex {
 public:
  std::uint32_t find_or_insert(const Coord& c) {
    if ((coords_.size() + 1) * 2 > slots_.size()) grow();
    std::size_t mask = slots_.size() - 1;
    for (std::size_t i = hash(c) & mask;; i = (i + 1) & mask) {
      std::uint32_t id = slots_[i];
      if (id == kEmpty) {
        slots_[i] = static_cast<std::uint32_t>(coords_.size());
        coords_.push_back(c);
        return slots_[i];
      }
      if (coords_[id] == c) return id;
    }
  }
  // The id of a voxel already in the index, or kAbsent. Never changes the index, so threads may share it.
  static constexpr std::uint32_t kAbsent = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t find(const Coord& c) const {
    if (slots_.empty()) return kAbsent;
    std::size_t mask = slots_.size() - 1;
    for (std::size_t i = hash(c) & mask;; i = (i + 1) & mask) {
      std::uint32_t id = slots_[i];
      if (id == kEmpty || coords_[id] == c) return id;  // kEmpty == kAbsent
    }
  }
  const std::vector<Coord>& coords() const { return coords_; }

 private:
  static constexpr std::uint32_t kEmpty = kAbsent;
  static std::size_t hash(const Coord& c) {
    std::uint64_t h = std::uint64_t(std::uint32_t(c.x)) * 0x9E3779B97F4A7C15ull;
    h ^= std::uint64_t(std::uint32_t(c.y)) * 0xC2B2AE3D27D4EB4Full;
    h ^= std::uint64_t(std::uint32_t(c.z)) * 0x165667B19E3779F9ull;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
  void grow() {
    slots_.assign(std::max<std::size_t>(64, slots_.size() * 2), kEmpty);
    std::size_t mask = slots_.size() - 1;
    for (std::uint32_t id = 0; id < coords_.size(); ++id) {
      std::size_t i = hash(coords_[id]) & mask;
      while (slots_[i] != kEmpty) i = (i + 1) & mask;
      slots_[i] = id;
    }
  }
  std::vector<std::uint32_t> slots_;
  std::vector<Coord> coords_;
};

// A complete VoxelIndex shared by threads that voxelise at once (a Sink's index for voxelize_streamline):
// a voxel missing from it gets VoxelIndex::kAbsent instead of a new id.
struct SharedVoxelIndex {
  const VoxelIndex* index = nullptr;
  std::uint32_t find_or_insert(const Coord& c) const { return index->find(c); }
};

// A voxline before its vertices are placed: an optional synthetic first point, then source points.
struct TempVoxline {
  std::uint32_t voxel;      // chunk-local voxel id
  std::uint32_t src_count;  // source points after the optional synthetic point
  std::uint64_t src_first;  // first source point index
  std::uint64_t synthetic;  // index into Chunk::synthetic_xyz, or kNoSynthetic
  std::uint32_t own() const { return src_count + (synthetic != kNoSynthetic ? 1u : 0u); }
};

struct Grid {
  double origin[3];
  double size;
  // voxel_coordinate() (spec §6.1) of a source point. Every point is >= the origin, so the quotient is
  // >= 0 and below the grid size (< 2^31), where truncation is floor: this avoids a floor() library
  // call per coordinate (the baseline x86-64 ISA has no rounding instruction). (A product with 1 / size,
  // divided only next to a face, measured 15 % slower: the three divisions pipeline.)
  Coord voxel_of(const float* p) const {
    return {static_cast<std::int32_t>((static_cast<double>(p[0]) - origin[0]) / size),
            static_cast<std::int32_t>((static_cast<double>(p[1]) - origin[1]) / size),
            static_cast<std::int32_t>((static_cast<double>(p[2]) - origin[2]) / size)};
  }
};

inline int chebyshev(const Coord& a, const Coord& b) {
  return std::max({std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(a.z - b.z)});
}

// Appends the voxlines of one streamline (Algorithm 1, with face splitting of long steps: spec §6.3) to
// `ch`, any struct with the members `VoxelIndex index`, `std::vector<TempVoxline> voxlines`,
// `std::vector<float> synthetic_xyz` and `bool too_many_synthetic`; sets the last and stops when the
// synthetic points would exceed `synthetic_limit`.
template <typename Sink>
void voxelize_streamline(const Grid& grid, const float* pts, std::uint64_t first, std::uint64_t n, Sink& ch,
                         std::uint64_t synthetic_limit) {
  if (n == 0) return;
  Coord current = grid.voxel_of(pts + 3 * first);
  TempVoxline open{ch.index.find_or_insert(current), 0, first, kNoSynthetic};
  auto close = [&](std::uint64_t end_point) {
    open.src_count = static_cast<std::uint32_t>(end_point - open.src_first);
    ch.voxlines.push_back(open);
  };
  for (std::uint64_t i = first + 1; i < first + n; ++i) {
    Coord next = grid.voxel_of(pts + 3 * i);
    if (next == current) continue;
    if (chebyshev(current, next) <= 1) {
      close(i);
      current = next;
      open = {ch.index.find_or_insert(current), 0, i, kNoSynthetic};
      continue;
    }
    // Long step a -> b: cross the faces in order of the line parameter t.
    const float* a = pts + 3 * (i - 1);
    const float* b = pts + 3 * i;
    struct Crossing {
      double t;
      int axis;
      int step;
    };
    const std::int32_t from[3] = {current.x, current.y, current.z};
    const std::int32_t to[3] = {next.x, next.y, next.z};
    // Check the budget before allocating: one step can cross billions of faces (found by fuzzing).
    std::uint64_t faces = 0;
    for (int c = 0; c < 3; ++c) faces += static_cast<std::uint64_t>(std::abs(std::int64_t(to[c]) - from[c]));
    if (ch.synthetic_xyz.size() / 3 + faces > synthetic_limit) {
      ch.too_many_synthetic = true;
      return;
    }
    std::vector<Crossing> crossings;
    crossings.reserve(faces);
    for (int c = 0; c < 3; ++c) {
      int step = to[c] > from[c] ? 1 : -1;
      double da = static_cast<double>(a[c]), db = static_cast<double>(b[c]);
      for (std::int32_t k = from[c]; k != to[c]; k += step) {
        // the face between voxel k and k + step
        double plane = grid.origin[c] + grid.size * static_cast<double>(step > 0 ? k + 1 : k);
        double t = (plane - da) / (db - da);
        crossings.push_back({std::clamp(t, 0.0, 1.0), c, step});
      }
    }
    std::stable_sort(crossings.begin(), crossings.end(),
                     [](const Crossing& x, const Crossing& y) { return x.t < y.t; });
    std::int32_t at[3] = {from[0], from[1], from[2]};
    for (std::size_t k = 0; k < crossings.size();) {
      double t = crossings[k].t;
      for (; k < crossings.size() && crossings[k].t == t; ++k) at[crossings[k].axis] += crossings[k].step;
      close(i);
      std::uint64_t s = ch.synthetic_xyz.size() / 3;
      for (int c = 0; c < 3; ++c) {
        double da = static_cast<double>(a[c]), db = static_cast<double>(b[c]);
        ch.synthetic_xyz.push_back(static_cast<float>(da + t * (db - da)));
      }
      // Where the point lies on its step, for interpolating per-point values (in-memory conversion only).
      if constexpr (requires { ch.synthetic_t; }) ch.synthetic_t.push_back(t);
      open = {ch.index.find_or_insert({at[0], at[1], at[2]}), 0, i, s};
    }
    if (ch.synthetic_xyz.size() / 3 > synthetic_limit) {
      ch.too_many_synthetic = true;
      return;
    }
    current = next;
  }
  close(first + n);
}

}  // namespace vxl::detail
