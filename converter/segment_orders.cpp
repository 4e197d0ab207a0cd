#include "segment_orders.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <thread>

#include "error.h"

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
  throw Error(ErrorKind::Usage, "", std::nullopt, "unknown order set '" + name + "' (expected axis or axis+diag)");
}

namespace {

// Order-preserving map of a double to an unsigned integer (negative numbers flip all bits).
std::uint64_t sortable_bits(double d) {
  std::uint64_t u;
  std::memcpy(&u, &d, 8);
  return (u & 0x8000000000000000ull) ? ~u : (u | 0x8000000000000000ull);
}

struct KeyedSegment {
  std::uint64_t key;  // sortable_bits of the exact double key
  std::uint32_t local;
};

// Stable LSD radix sort by key, 8 bits a pass. Items arrive in ascending local index, so stability gives
// the spec's tie rule (ascending index) for free. Passes whose digit is the same for every item are
// skipped: keys are sums of two floats, whose low mantissa bytes are zero in a double, and the keys of
// one voxel share their high bytes, so typically only 3-4 of the 8 passes run.
void radix_sort(std::vector<KeyedSegment>& items, std::vector<KeyedSegment>& scratch) {
  const std::size_t n = items.size();
  if (n < 2) return;
  scratch.resize(n);
  std::uint64_t all_or = 0, all_and = ~0ull;
  for (const KeyedSegment& k : items) {
    all_or |= k.key;
    all_and &= k.key;
  }
  const std::uint64_t varying = all_or ^ all_and;
  for (int shift = 0; shift < 64; shift += 8) {
    if (((varying >> shift) & 0xFF) == 0) continue;
    std::size_t count[257] = {};
    for (const KeyedSegment& k : items) ++count[((k.key >> shift) & 0xFF) + 1];
    for (int b = 0; b < 256; ++b) count[b + 1] += count[b];
    for (const KeyedSegment& k : items) scratch[count[(k.key >> shift) & 0xFF]++] = k;
    items.swap(scratch);
  }
}

}  // namespace

BuiltOrders build_orders(VoxelizedTractogram& vt, const OrderSetSpec& set, unsigned threads, const ProgressFn& progress) {
  BuiltOrders out;
  const std::uint32_t k_count = static_cast<std::uint32_t>(set.directions.size());
  for (const auto& d : set.directions) out.directions.push_back({{d[0], d[1], d[2]}, 0});
  vt.meta.stored_order_count = k_count;
  vt.meta.order_set = static_cast<std::uint32_t>(set.kind);

  std::uint64_t total = 0;
  for (VoxelEntry& v : vt.voxels) {
    v.flags = order_width_code(v.vertex_count);
    v.order_offset = total;
    total += order_bytes(v.vertex_count, v.segment_count, k_count);
  }
  out.bytes.assign(total, 0);

  // Axis directions sort by one exact component sum, as in the paper; others by a dot product.
  std::vector<int> axis_of(k_count, -1);
  for (std::uint32_t k = 0; k < k_count; ++k)
    for (int c = 0; c < 3; ++c)
      if (set.directions[k][c] == 1.0f && set.directions[k][(c + 1) % 3] == 0.0f && set.directions[k][(c + 2) % 3] == 0.0f)
        axis_of[k] = c;

  std::atomic<std::size_t> next{0};
  std::atomic<std::size_t> done{0};
  auto worker = [&](bool reports) {
    std::vector<std::uint32_t> starts;
    std::vector<KeyedSegment> keyed, scratch;
    for (std::size_t i; (i = next++) < vt.voxels.size();) {
      const VoxelEntry& v = vt.voxels[i];
      starts.clear();
      for (std::uint32_t e = 0; e < v.vertex_count; ++e)
        if (!vt.is_voxline_end[v.vertex_first + e]) starts.push_back(e);
      const float* block = vt.vertices.data() + 3 * v.vertex_first;
      const std::uint32_t width = order_entry_width(v.vertex_count);
      std::uint8_t* dst = out.bytes.data() + v.order_offset;
      for (std::uint32_t k = 0; k < k_count; ++k) {
        keyed.resize(starts.size());
        const auto& d = set.directions[k];
        for (std::size_t n = 0; n < starts.size(); ++n) {
          const float* a = block + 3 * starts[n];
          double key;
          if (axis_of[k] >= 0) {
            key = double(a[axis_of[k]]) + double(a[axis_of[k] + 3]);
          } else {
            key = 0;
            for (int c = 0; c < 3; ++c) key += (double(a[c]) + double(a[c + 3])) * double(d[c]);
          }
          keyed[n] = {sortable_bits(key + 0.0), starts[n]};  // + 0.0 folds -0 into +0
        }
        radix_sort(keyed, scratch);
        for (std::size_t n = 0; n < keyed.size(); ++n, dst += width) std::memcpy(dst, &keyed[n].local, width);
      }
      std::size_t d = ++done;
      if (reports && progress && (d & 63) == 0) progress("ordering", double(d) / double(vt.voxels.size()));
    }
  };
  unsigned n_threads = std::max(1u, resolve_threads(threads));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < n_threads; ++t) pool.emplace_back(worker, false);
  worker(true);
  for (auto& th : pool) th.join();
  if (progress) progress("ordering", 1.0);
  return out;
}

}  // namespace vxl
