#include "converter/convert/segment_sort.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "format/base/float_bits.h"

namespace vxl::detail {

std::uint64_t sortable_bits(double d) {
  std::uint64_t u;
  std::memcpy(&u, &d, 8);
  const std::uint64_t negative = 0 - (u >> 63);  // all ones for a negative number (no branch: signs mix)
  const std::uint64_t magnitude = u & 0x7FFFFFFFFFFFFFFFull;
  return ((magnitude ^ negative) - negative) ^ 0x8000000000000000ull;  // -0 and +0 map alike
}

namespace {

// Stable LSD radix sort of `items` by the bits [first_bit, first_bit + bits) of key(item), in as few
// passes of at most digit_bits(n, bits) bits as cover them; passes whose digit is the same for every item are
// skipped. Items arrive in ascending block-local index, so stability gives the spec's tie rule
// (ascending index) for free.
//
// Fewer, wider passes win while the buckets stay few next to the items: a voxel of the 1M synthetic set
// (10 mm voxels, ~60k segments, keys of 21-28 bits) sorts in 2 passes of up to 14 bits instead of 3 of up
// to 11, and its orders took 1.27 instead of 1.54 s of CPU. Each pass also walks all its buckets, so small
// voxels keep narrow digits.
//
// Past about 2M items (16 MB, more than the caches hold) every pass goes to main memory, and 14-bit digits
// scatter each pass over 16k places at once: where the keys need more than one pass anyway, 11-bit digits,
// though they may take a pass more, sorted the largest voxels of the 10M synthetic set (up to 7.7M
// segments, keys of 21-39 bits) 3-5 % faster.
constexpr int kMinDigitBits = 8, kMaxDigitBits = 14;
constexpr int kMaxPasses = (64 + kMinDigitBits - 1) / kMinDigitBits;
constexpr std::size_t kUncachedItems = std::size_t(1) << 21;
constexpr int kUncachedDigitBits = 11;
int digit_bits(std::size_t n, int key_bits) {
  const int bits = std::clamp(static_cast<int>(std::bit_width(n)) - 2, kMinDigitBits, kMaxDigitBits);
  return n > kUncachedItems && key_bits > bits ? std::min(bits, kUncachedDigitBits) : bits;
}

// One read of the items fills every pass's histogram (P known at compile time, so the loop unrolls).
template <int P, typename Item, typename Key>
void histograms(const std::vector<Item>& items, std::uint32_t* count, Key key, int first_bit, int digit) {
  const std::uint64_t mask = (1ull << digit) - 1;
  for (const Item& x : items) {
    const std::uint64_t k = key(x) >> first_bit;
    for (int p = 0; p < P; ++p) ++count[(std::size_t(p) << digit) + ((k >> (p * digit)) & mask)];
  }
}

template <typename Item, typename Key>
void radix_sort_bits(std::vector<Item>& items, std::vector<Item>& scratch, std::vector<std::uint32_t>& count, Key key,
                     int first_bit, int bits) {
  const std::size_t n = items.size();
  const int passes = (bits + digit_bits(n, bits) - 1) / digit_bits(n, bits);
  const int digit = (bits + passes - 1) / passes;
  const std::uint64_t mask = (1ull << digit) - 1;
  count.assign(std::size_t(passes) << digit, 0u);
  switch (passes) {
    case 1: histograms<1>(items, count.data(), key, first_bit, digit); break;
    case 2: histograms<2>(items, count.data(), key, first_bit, digit); break;
    case 3: histograms<3>(items, count.data(), key, first_bit, digit); break;
    case 4: histograms<4>(items, count.data(), key, first_bit, digit); break;
    case 5: histograms<5>(items, count.data(), key, first_bit, digit); break;
    case 6: histograms<6>(items, count.data(), key, first_bit, digit); break;
    case 7: histograms<7>(items, count.data(), key, first_bit, digit); break;
    default: static_assert(kMaxPasses == 8); histograms<8>(items, count.data(), key, first_bit, digit);
  }
  scratch.resize(n);
  for (int p = 0; p < passes; ++p) {
    std::uint32_t* c = count.data() + (std::size_t(p) << digit);
    const int shift = first_bit + p * digit;
    if (c[(key(items[0]) >> shift) & mask] == n) continue;  // one bucket holds everything: nothing moves
    std::uint32_t sum = 0;
    for (std::size_t b = 0; b <= mask; ++b) sum += std::exchange(c[b], sum);
    for (const Item& x : items) scratch[c[(key(x) >> shift) & mask]++] = x;
    items.swap(scratch);
  }
}

// Writes block-local indices as `bits`-bit entries from the lowest bit of dst on (spec §5.5 ORDB), four
// bytes at a time; the last bytes alone, so nothing past the array's order_array_bytes is touched.
template <typename Local>
std::uint8_t* put_entries(std::uint8_t* dst, std::uint32_t bits, std::size_t n, Local&& local) {
  std::uint64_t pending = 0;  // bits not yet stored, lowest first
  std::uint32_t filled = 0;   // < 32 between entries
  for (std::size_t i = 0; i < n; ++i) {
    pending |= std::uint64_t(local(i)) << filled;
    filled += bits;
    if (filled >= 32) {
      const auto word = static_cast<std::uint32_t>(pending);
      std::memcpy(dst, &word, 4);
      dst += 4;
      pending >>= 32;
      filled -= 32;
    }
  }
  for (; filled > 0; filled = filled > 8 ? filled - 8 : 0, pending >>= 8) *dst++ = static_cast<std::uint8_t>(pending);
  return dst;
}

// Sorts s.keys — each a `bits`-bit key above a block-local index of `index_bits` bits — by key (ties keep the
// ascending index order they come in) and writes their indices as `entry_bits`-bit entries to dst.
std::uint8_t* sort_indexed_keys(SortScratch& s, int index_bits, int bits, std::uint32_t entry_bits, std::uint8_t* dst) {
  radix_sort_bits(
      s.keys, s.packed_tmp, s.counts, [](std::uint64_t x) { return x; }, index_bits, bits);
  const std::uint64_t index_mask = (1ull << index_bits) - 1;
  return put_entries(dst, entry_bits, s.keys.size(),
                     [&](std::size_t i) { return static_cast<std::uint32_t>(s.keys[i] & index_mask); });
}

// The exponent of the lowest set bit of a finite, nonzero float: it is a multiple of 2 to that power.
int lowest_bit_exponent(float f) {
  const auto bits = float_bits(f);
  const std::uint32_t biased = (bits >> 23) & 0xFFu, fraction = bits & 0x7FFFFFu;
  constexpr int kBias = 127, kFractionBits = 23;
  if (biased == 0) return 1 - kBias - kFractionBits + std::countr_zero(fraction);  // subnormal
  return int(biased) - kBias - kFractionBits + std::countr_zero(fraction | 0x800000u);
}

}  // namespace

// Writes the order of one voxel's segments (block-local `starts`, ascending) by ascending `s.keys`
// (which differ in the bits of `varying`), ties by ascending index, to `dst`; returns the end of what
// it wrote.
std::uint8_t* sort_segments(const std::vector<std::uint32_t>& starts, std::uint32_t vertex_count,
                            std::uint32_t entry_bits, std::uint64_t varying, SortScratch& s, std::uint8_t* dst) {
  const std::size_t n = starts.size();
  if (n < 2 || varying == 0) return put_entries(dst, entry_bits, n, [&](std::size_t i) { return starts[i]; });

  // All keys share the bits above the highest varying bit and below the lowest, so the varying field
  // alone orders them. Packed above the block-local index it makes one 8-byte item per segment, half
  // the traffic of key + index. The field is typically 3 bytes of mantissa (sums of two floats).
  const int low = std::countr_zero(varying), bits = 64 - std::countl_zero(varying) - low;
  const int index_bits = std::bit_width(vertex_count - 1);  // vertex_count >= 2 here
  if (bits + index_bits <= 64) {
    // In place: one array less to fill and to keep in cache (the largest voxels' do not fit).
    const std::uint64_t field = (1ull << bits) - 1;  // bits < 64 here
    for (std::size_t i = 0; i < n; ++i) s.keys[i] = ((s.keys[i] >> low) & field) << index_bits | starts[i];
    return sort_indexed_keys(s, index_bits, bits, entry_bits, dst);
  }
  s.keyed.reserve(s.max_vertices);
  s.keyed_tmp.reserve(s.max_vertices);
  s.keyed.resize(n);
  for (std::size_t i = 0; i < n; ++i) s.keyed[i] = {s.keys[i], starts[i]};
  radix_sort_bits(
      s.keyed, s.keyed_tmp, s.counts, [](const KeyedSegment& k) { return k.key; }, low, bits);
  return put_entries(dst, entry_bits, n, [&](std::size_t i) { return s.keyed[i].local; });
}

void QuantumSumKeys::prepare(const std::array<float, kPackedSteps + 1>& decoded) {
  usable_ = false;
  // Each d is an integer number of the largest power of two that divides them all, and a key (an exact sum in
  // double) the sum of two such integers. That unit is at least the least ulp among them, and for a voxel across
  // 0 it is coarser than the ulps of its values near 0 (exact cancellations of lo and q * step): measuring in the
  // least ulp instead would leave such a voxel's buckets too wide for the shortcut.
  int unit_exponent = std::numeric_limits<int>::max();
  for (const float d : decoded) {
    if (!std::isfinite(d)) return;
    if (d != 0) unit_exponent = std::min(unit_exponent, lowest_bit_exponent(d));
  }
  if (unit_exponent == std::numeric_limits<int>::max()) return;  // all zero: one key, nothing to rank
  const double per_unit = std::ldexp(1.0, -unit_exponent);       // a power of two: the products are exact
  constexpr double kMaxUnits = 0x1p50;                           // the sums stay exact in double and in int64
  for (std::uint32_t q = 0; q <= kPackedSteps; ++q) {
    const double units = double(decoded[q]) * per_unit;
    if (!(std::fabs(units) < kMaxUnits)) return;
    units_[q] = static_cast<std::int64_t>(units);
  }
  // The buckets from the straight line through the first and last quantum, widened by how far the units
  // stray from it and by a margin for rounding: an estimate, checked below and key by key.
  const double first = double(units_[0]), slope = (double(units_[kPackedSteps]) - first) / kPackedSteps;
  double below = 0, above = 0;
  for (std::uint32_t q = 0; q <= kPackedSteps; ++q) {
    const double off = double(units_[q]) - (first + double(q) * slope);
    below = std::min(below, off);
    above = std::max(above, off);
  }
  span_ = static_cast<std::uint64_t>(2 * (above - below)) + 5;
  offset_bits_ = std::bit_width(span_);
  if (offset_bits_ > kMaxOffsetBits) return;
  for (std::uint32_t sum = 0; sum < kSums; ++sum) {
    const double least_sum = 2 * first + double(sum) * slope + 2 * below;  // |least_sum| < 2^52
    floor_[sum] = static_cast<std::int64_t>(least_sum) - 3;                // truncation, then the margin covers floor
  }
  for (std::uint32_t sum = 0; sum + 1 < kSums; ++sum)
    if (floor_[sum] + static_cast<std::int64_t>(span_) >= floor_[sum + 1]) return;  // buckets that touch
  usable_ = true;
}

std::uint8_t* QuantumSumKeys::sort(const std::vector<std::uint32_t>& starts, const std::uint32_t* words, int axis,
                                   std::uint32_t vertex_count, std::uint32_t entry_bits, SortScratch& s,
                                   std::uint8_t* dst) const {
  if (!usable_) return nullptr;
  const std::size_t n = starts.size();
  const int shift = 10 * axis, key_bits = kSumBits + offset_bits_;
  std::uint64_t outside = 0;  // any offset past the span
  auto key_of = [&](std::uint32_t a) {
    const std::uint32_t qa = (words[a] >> shift) & kPackedAxisMask, qb = (words[a + 1] >> shift) & kPackedAxisMask;
    const std::uint32_t sum = qa + qb;
    const auto offset = static_cast<std::uint64_t>(units_[qa] + units_[qb] - floor_[sum]);  // wraps if below
    outside |= offset > span_ ? 1 : 0;
    return std::uint64_t(sum) << offset_bits_ | std::min(offset, span_);
  };
  if (n < kCountingSortItems) {  // few items for the buckets: the key packed with the index, radix sorted
    const int index_bits = std::bit_width(std::max<std::uint32_t>(vertex_count, 2) - 1);
    s.keys.resize(n);
    for (std::size_t i = 0; i < n; ++i) s.keys[i] = key_of(starts[i]) << index_bits | starts[i];
    if (outside != 0) return nullptr;
    return sort_indexed_keys(s, index_bits, key_bits, entry_bits, dst);
  }
  // One counting sort by the whole key: a pass over 4-byte indices instead of radix passes over 8-byte items.
  s.bucket_keys.reserve(s.max_vertices);
  s.bucketed.reserve(s.max_vertices);
  s.bucket_keys.resize(n);
  s.counts.assign(std::size_t(1) << key_bits, 0u);
  for (std::size_t i = 0; i < n; ++i) ++s.counts[s.bucket_keys[i] = static_cast<std::uint16_t>(key_of(starts[i]))];
  if (outside != 0) return nullptr;
  std::uint32_t sum = 0;
  for (std::uint32_t& c : s.counts) sum += std::exchange(c, sum);
  s.bucketed.resize(n);
  for (std::size_t i = 0; i < n; ++i) s.bucketed[s.counts[s.bucket_keys[i]]++] = starts[i];
  return put_entries(dst, entry_bits, n, [&](std::size_t i) { return s.bucketed[i]; });
}

std::uint64_t sort_scratch_bytes(std::uint32_t max_vertices) {
  // Per segment (fewer than vertices): keys and packed_tmp (u64); for a voxel whose keys do not pack,
  // keyed and keyed_tmp (16 bytes); for QuantumSumKeys' counting sort, bucket_keys (u16) and bucketed (u32).
  // Plus the histograms.
  const std::uint64_t per_vertex =
      2 * sizeof(std::uint64_t) + 2 * sizeof(KeyedSegment) + sizeof(std::uint16_t) + sizeof(std::uint32_t);
  return per_vertex * max_vertices + std::uint64_t(kMaxPasses) * (1u << kMaxDigitBits) * sizeof(std::uint32_t);
}

}  // namespace vxl::detail
