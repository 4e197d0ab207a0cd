// The synthetic generator's scene (synth.cpp draws its streamlines): tube-shaped bundles along smooth centre
// curves inside the brain ellipsoid — association, projection and commissural pairs, U-fibres and a few named
// bundles — drawn from one random stream in a fixed order, so that a seed gives the same scene everywhere.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "converter/synth/synth_random.h"

namespace vxl::synth {

// One sample of a centre curve, every 1 mm of arc length: position, a rotation-minimising frame (n, b)
// perpendicular to the tangent, and the tube radius.
struct Sample {
  double c[3];
  double n[3];
  double b[3];
  double r;
};

struct Bundle {
  std::vector<Sample> samples;  // count() samples plus one copy of the last (so s0 + k + 1 is valid)
  double weight = 1;
  std::uint32_t count() const { return static_cast<std::uint32_t>(samples.size() - 1); }
};

// The scene: its bundles, long ones first, and what a streamline needs to pick one.
struct Layout {
  std::vector<Bundle> bundles;
  // Long bundles sorted by sample count, with cumulative weights, for "a long bundle of >= L samples".
  std::vector<std::uint32_t> long_ids;
  std::vector<std::uint32_t> long_counts;
  std::vector<double> long_cum;  // size long_ids.size() + 1
  std::uint32_t max_long_points = 0;
  std::vector<std::uint32_t> u_ids;
  std::vector<double> u_cum;
  std::size_t long_bundle_count = 0, u_bundle_count = 0;
  std::vector<std::string> named_bundles;
};

inline constexpr double kUFraction = 0.12;  // share of streamlines that are U-fibres
// Long streamlines have 20 + floor(Gamma(2, kLengthTheta)) points; with 12% U-fibres of ~31 points the
// overall mean is ~56.
inline constexpr double kLengthTheta = 21.0;
// Offsets: a base point in the unit disc plus a wander of +-kWander per component, times the radius.
// Max offset = radius * (1 + flare) * (1 + kWander * sqrt 2): long <= 3 * 1.4 * 1.36 = 5.7 mm, less than
// the 7.2 mm margin between the 0.88-scaled ellipsoid K and the brain ellipsoid E = K / 0.88 (E = K +
// (1/0.88 - 1) K, and K contains a ball of radius 0.88 * 60 mm, so E contains K + a ball of (1 - 0.88) *
// 60 mm); U-fibres <= 1.4 * 1.2 * 1.36 = 2.3 mm of a 6 mm margin. Interpolated frames are at most unit
// length and within ~0.3% of orthogonal. So every point is inside the brain ellipsoid by construction.
inline constexpr double kWander = 0.25;
inline constexpr std::uint32_t kWanderKnotSpacing = 16;  // mm between wander knots (a power of two)

Layout build_layout(std::uint64_t seed);

// Weighted pick among ids[first..] with cumulative weights cum (size ids.size() + 1).
std::uint32_t pick(Rng& rng, const std::vector<std::uint32_t>& ids, const std::vector<double>& cum, std::size_t first);

}  // namespace vxl::synth
