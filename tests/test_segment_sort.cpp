// The ranking of a packed block's axis keys by quantum sum (QuantumSumKeys) against the general sort of the
// keys themselves (sort_segments): the same bytes wherever the shortcut is taken, and no shortcut where its
// buckets would overlap.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <limits>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "converter/convert/segment_sort.h"
#include "format/vxl_layout.h"
#include "format/vxl_positions.h"

using namespace vxl;
using detail::QuantumSumKeys;
using detail::SortScratch;

namespace {

struct Block {
  std::vector<std::uint32_t> words;   // x quanta only: the other axes do not enter an x order
  std::vector<std::uint32_t> starts;  // segments: every vertex but a voxline's last
};

// `vertices` random quanta of axis `axis` in voxlines of 2-40 vertices (the other axes' bits random too). Runs of
// equal quanta and of neighbours make ties.
Block random_block(std::uint32_t vertices, std::uint32_t seed, int axis) {
  std::mt19937 rng(seed);
  Block b;
  std::uint32_t left = 0;
  for (std::uint32_t e = 0; e < vertices; ++e) {
    if (left == 0) left = std::uniform_int_distribution<std::uint32_t>(2, 40)(rng);
    const std::uint32_t repeated = e > 0 ? (b.words.back() >> (10 * axis)) & kPackedAxisMask : 0;
    const std::uint32_t q = rng() % 4 == 0 && e > 0 ? repeated : rng() % (kPackedSteps + 1);
    const std::uint32_t others = rng() & 0x3FFFFFFFu & ~(kPackedAxisMask << (10 * axis));
    b.words.push_back(others | q << (10 * axis));
    if (--left > 0 && e + 1 < vertices) b.starts.push_back(e);
  }
  return b;
}

std::array<float, kPackedSteps + 1> decoded_axis(float lo, float hi) {
  VoxelEntry v{};
  v.tight_min[0] = lo;
  v.tight_max[0] = hi;
  const VertexPacker packer(v);
  std::array<float, kPackedSteps + 1> d{};
  for (std::uint32_t q = 0; q <= kPackedSteps; ++q) d[q] = packer.decode_axis(0, q);
  return d;
}

// The order sort_segments writes from the keys themselves (the path for any direction).
std::vector<std::uint8_t> general_order(const Block& b, const std::array<float, kPackedSteps + 1>& d, int axis,
                                        std::uint32_t entry_bits) {
  auto q = [&](std::uint32_t e) { return (b.words[e] >> (10 * axis)) & kPackedAxisMask; };
  SortScratch s;
  s.keys.resize(b.starts.size());
  std::uint64_t all_or = 0, all_and = ~0ull;
  for (std::size_t i = 0; i < b.starts.size(); ++i) {
    const std::uint32_t a = b.starts[i];
    s.keys[i] = detail::sortable_bits(double(d[q(a)]) + double(d[q(a + 1)]));
    all_or |= s.keys[i];
    all_and &= s.keys[i];
  }
  std::vector<std::uint8_t> out(order_array_bytes(b.starts.size(), entry_bits) + 8, 0xA5);
  detail::sort_segments(b.starts, static_cast<std::uint32_t>(b.words.size()), entry_bits, all_or ^ all_and, s,
                        out.data());
  return out;
}

struct Case {
  const char* name;
  float lo, hi;
  bool shortcut;  // whether the buckets are apart
};
void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

class QuantumSums : public ::testing::TestWithParam<Case> {};

TEST_P(QuantumSums, RankTheSegmentsAsTheirKeysDo) {
  const Case c = GetParam();
  const std::array<float, kPackedSteps + 1> d = decoded_axis(c.lo, c.hi);
  QuantumSumKeys sums;
  sums.prepare(d);
  EXPECT_EQ(sums.usable(), c.shortcut);
  // Below and above the size where the counting sort takes over from the radix sort; along each axis.
  for (const std::uint32_t vertices : {3u, 5000u, 150000u}) {
    const int axis = static_cast<int>(vertices % 3);
    const Block b = random_block(vertices, vertices + 7, axis);
    const std::uint32_t bits = order_entry_bits(vertices, OrderPacking::Bits);
    const std::vector<std::uint8_t> expected = general_order(b, d, axis, bits);
    std::vector<std::uint8_t> got(expected.size(), 0xA5);
    SortScratch s;
    const std::uint8_t* end = sums.sort(b.starts, b.words.data(), axis, vertices, bits, s, got.data());
    if (!c.shortcut) {
      EXPECT_EQ(end, nullptr) << vertices;
      continue;
    }
    ASSERT_NE(end, nullptr) << vertices;
    EXPECT_EQ(end - got.data(), static_cast<std::ptrdiff_t>(order_array_bytes(b.starts.size(), bits))) << vertices;
    EXPECT_EQ(got, expected) << vertices << " vertices";
  }
}

INSTANTIATE_TEST_SUITE_P(
    Extremes, QuantumSums,
    ::testing::Values(Case{"Positive", 10.3f, 20.1f, true}, Case{"Negative", -61.933f, -51.933f, true},
                      Case{"AcrossAPowerOfTwo", 60.5f, 70.5f, true}, Case{"AThousandAway", 1000.0f, 1010.0f, true},
                      Case{"Fine", 0.001f, 0.002f, true}, Case{"Denormal", 0.0f, 1.0e-40f, true},
                      // Values near 0 are exact differences of lo and q * step: no finer than those.
                      Case{"AcrossZero", -2.188f, 7.812f, true}, Case{"AroundZero", -5.0f, 5.0f, true},
                      // But here lo's ulp is far finer than those of the larger values: the buckets spread too wide.
                      Case{"AcrossZeroNearItsLowEnd", -0.3f, 9.7f, false},
                      // A quantum narrower than a few ulps: the buckets touch.
                      Case{"NarrowerThanItsUlps", 50.0f, 50.0001f, false},
                      Case{"AMillionAway", 1.0e6f, 1.0e6f + 10, false}, Case{"Flat", 5.0f, 5.0f, false}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.name); });

// Tables no packed block decodes to are refused rather than ranked, as is one not prepared.
TEST(QuantumSumKeysPrepare, RefusesTablesItCannotRankExactly) {
  std::array<float, kPackedSteps + 1> d = decoded_axis(10.0f, 20.0f);
  QuantumSumKeys sums;
  sums.prepare(d);
  ASSERT_TRUE(sums.usable());
  sums.clear();
  EXPECT_FALSE(sums.usable());
  d[7] = std::numeric_limits<float>::quiet_NaN();
  sums.prepare(d);
  EXPECT_FALSE(sums.usable());
  d = decoded_axis(10.0f, 20.0f);
  d[kPackedSteps] = std::numeric_limits<float>::infinity();
  sums.prepare(d);
  EXPECT_FALSE(sums.usable());
  // 2^-140 and 2^60: as units of the least power of two, 2^200 — past what sums exactly.
  d = decoded_axis(10.0f, 20.0f);
  d[0] = 0x1p-140f;
  d[kPackedSteps] = 0x1p60f;
  sums.prepare(d);
  EXPECT_FALSE(sums.usable());
}

}  // namespace
