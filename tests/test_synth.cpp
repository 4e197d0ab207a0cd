// The synthetic tractogram generator: determinism, shape and the prefix property.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <gtest/gtest.h>

#include "converter/synth/synth.h"
#include "format/base/checksum.h"

namespace {

using vxl::SynthSettings;
using vxl::Tractogram;

Tractogram synth(std::uint64_t n, std::uint64_t seed, unsigned threads = 0) {
  return vxl::synthesize_tractogram(SynthSettings{n, seed, threads});
}

bool same(const Tractogram& a, const Tractogram& b) {
  return a.offsets == b.offsets && a.positions.size() == b.positions.size() &&
         std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(float)) == 0;
}

// sum(((p - centre) / semi_axes)^2) for point k.
double ellipsoid_q(const Tractogram& t, std::uint64_t k) {
  double q = 0;
  for (int d = 0; d < 3; ++d) {
    const double v = (static_cast<double>(t.positions[3 * k + d]) - vxl::kSynthCentre[d]) / vxl::kSynthSemiAxes[d];
    q += v * v;
  }
  return q;
}

TEST(Synth, SameSeedIsBitIdentical) {
  const Tractogram a = synth(5000, 7), b = synth(5000, 7);
  ASSERT_EQ(a.streamline_count(), 5000u);  // two empty tractograms would be identical too
  ASSERT_GT(a.point_count(), 5000u * 10);
  EXPECT_TRUE(same(a, b));
}

TEST(Synth, ThreadCountDoesNotMatter) {
  // More than one work chunk (4096 streamlines), so threads really share the work.
  const Tractogram one = synth(10000, 3, 1);
  ASSERT_EQ(one.streamline_count(), 10000u);
  ASSERT_GT(one.point_count(), 10000u * 10);
  EXPECT_TRUE(same(one, synth(10000, 3, 2)));
  EXPECT_TRUE(same(one, synth(10000, 3, 5)));
}

TEST(Synth, DifferentSeedDiffers) {
  const Tractogram a = synth(2000, 1), b = synth(2000, 2);
  EXPECT_FALSE(same(a, b));
  // Not just a few values: the point clouds differ almost everywhere.
  const std::size_t n = std::min(a.positions.size(), b.positions.size());
  std::size_t equal = 0;
  for (std::size_t i = 0; i < n; ++i) equal += a.positions[i] == b.positions[i];
  EXPECT_LT(equal, n / 100);
}

TEST(Synth, PinnedOutput) {
  // Guards determinism across compilers, optimisation levels and platforms: these hashes were taken
  // with GCC 12 on x86-64 (and match Clang 14, -O0..-O3, -march=native). If the generator changes on
  // purpose, bump kSynthGeneratorVersion and update them.
  const Tractogram t = synth(1000, 1);
  EXPECT_EQ(t.point_count(), 54332u);
  EXPECT_EQ(vxl::xxh3_64(t.offsets.data(), t.offsets.size() * sizeof(std::uint64_t)), 0xb294e17a40121024ULL);
  EXPECT_EQ(vxl::xxh3_64(t.positions.data(), t.positions.size() * sizeof(float)), 0xb86a66ca43ed9545ULL);
}

TEST(Synth, ExactStreamlineCountAndOffsets) {
  for (std::uint64_t n : {0u, 1u, 2u, 17u, 4096u, 4097u}) {
    SCOPED_TRACE(n);
    const Tractogram t = synth(n, 11);
    ASSERT_EQ(t.streamline_count(), n);
    ASSERT_EQ(t.offsets.size(), n + 1);
    EXPECT_EQ(t.offsets.front(), 0u);
    EXPECT_EQ(t.offsets.back(), t.point_count());
    EXPECT_EQ(t.positions.size(), 3 * t.point_count());
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::uint64_t len = t.offsets[i + 1] - t.offsets[i];
      ASSERT_GE(len, vxl::kSynthMinPoints) << "streamline " << i;
      ASSERT_LE(len, vxl::kSynthMaxPoints) << "streamline " << i;
    }
  }
}

TEST(Synth, SourceInfo) {
  const Tractogram t = synth(10, 42);
  EXPECT_EQ(t.source.format, "synth");
  EXPECT_EQ(t.source.dtype, "float32");
  EXPECT_EQ(t.source.header.at("generator"), "voxlines-synth");
  EXPECT_EQ(t.source.header.at("version"), vxl::kSynthGeneratorVersion);
  EXPECT_EQ(t.source.header.at("streamlines").get<std::uint64_t>(), 10u);
  EXPECT_EQ(t.source.header.at("seed").get<std::uint64_t>(), 42u);
  EXPECT_TRUE(t.groups.empty());
  const auto names = t.source.header.at("named_bundles").get<std::vector<std::string>>();
  EXPECT_EQ(names, (std::vector<std::string>{"corpus callosum", "corticospinal tract", "cingulum", "arcuate fasciculus",
                                             "inferior fronto-occipital fasciculus"}));
}

TEST(Synth, MeanPointsPerStreamline) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Tractogram t = synth(20000, seed);
    const double mean = static_cast<double>(t.point_count()) / static_cast<double>(t.streamline_count());
    EXPECT_GE(mean, 50.0) << "seed " << seed;
    EXPECT_LE(mean, 62.0) << "seed " << seed;
  }
}

TEST(Synth, LengthsSpread) {
  const Tractogram t = synth(20000, 1);
  std::uint64_t shortest = UINT64_MAX, longest = 0, over100 = 0;
  for (std::uint64_t i = 0; i < t.streamline_count(); ++i) {
    const std::uint64_t len = t.offsets[i + 1] - t.offsets[i];
    shortest = std::min(shortest, len);
    longest = std::max(longest, len);
    over100 += len > 100;
  }
  EXPECT_EQ(shortest, vxl::kSynthMinPoints);
  EXPECT_GE(longest, 140u);
  EXPECT_GT(over100, t.streamline_count() / 50);  // a real tail, not just a few outliers
}

TEST(Synth, StepLengthsAboutOneMillimetre) {
  for (std::uint64_t seed : {1u, 5u}) {
    const Tractogram t = synth(20000, seed);
    double lo = 1e9, hi = 0;
    for (std::uint64_t i = 0; i < t.streamline_count(); ++i) {
      for (std::uint64_t k = t.offsets[i]; k + 1 < t.offsets[i + 1]; ++k) {
        double d2 = 0;
        for (int d = 0; d < 3; ++d) {
          const double v = static_cast<double>(t.positions[3 * k + 3 + d]) - t.positions[3 * k + d];
          d2 += v * v;
        }
        const double step = std::sqrt(d2);
        lo = std::min(lo, step);
        hi = std::max(hi, step);
      }
    }
    EXPECT_GE(lo, 0.5) << "seed " << seed;
    EXPECT_LE(hi, 1.5) << "seed " << seed;
  }
}

TEST(Synth, PointsInsideEllipsoid) {
  for (std::uint64_t seed : {1u, 9u}) {
    const Tractogram t = synth(20000, seed);
    double qmax = 0;
    for (std::uint64_t k = 0; k < t.point_count(); ++k) qmax = std::max(qmax, ellipsoid_q(t, k));
    EXPECT_LE(std::sqrt(qmax), vxl::kSynthEnlarge) << "seed " << seed;
    // By construction they even stay inside the brain ellipsoid itself, and reach near its surface.
    EXPECT_LE(std::sqrt(qmax), 1.0) << "seed " << seed;
    EXPECT_GE(std::sqrt(qmax), 0.85) << "seed " << seed;
  }
}

TEST(Synth, FillsBothHemispheresAndTheVolume) {
  const Tractogram t = synth(20000, 1);
  std::uint64_t left = 0, right = 0;
  double lo[3] = {1e9, 1e9, 1e9}, hi[3] = {-1e9, -1e9, -1e9};
  for (std::uint64_t k = 0; k < t.point_count(); ++k) {
    (t.positions[3 * k] < 0 ? left : right) += 1;
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], static_cast<double>(t.positions[3 * k + d]));
      hi[d] = std::max(hi[d], static_cast<double>(t.positions[3 * k + d]));
    }
  }
  EXPECT_GT(left, t.point_count() / 3);
  EXPECT_GT(right, t.point_count() / 3);
  for (int d = 0; d < 3; ++d) {
    // Spans most of the ellipsoid along every axis.
    EXPECT_LT(lo[d], vxl::kSynthCentre[d] - 0.7 * vxl::kSynthSemiAxes[d]) << "axis " << d;
    EXPECT_GT(hi[d], vxl::kSynthCentre[d] + 0.7 * vxl::kSynthSemiAxes[d]) << "axis " << d;
  }
}

TEST(Synth, PrefixProperty) {
  // Streamline i depends only on (seed, i): the first K of a larger set are the set of K.
  const Tractogram big = synth(9000, 4);
  for (std::uint64_t k : {1u, 1000u, 4097u}) {
    SCOPED_TRACE(k);
    const Tractogram small = synth(k, 4);
    ASSERT_EQ(small.streamline_count(), k);
    EXPECT_TRUE(std::equal(small.offsets.begin(), small.offsets.end(), big.offsets.begin()));
    ASSERT_LE(small.positions.size(), big.positions.size());
    EXPECT_EQ(std::memcmp(small.positions.data(), big.positions.data(), small.positions.size() * sizeof(float)), 0);
  }
}

}  // namespace
