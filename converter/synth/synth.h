// A deterministic synthetic whole-brain-like tractogram, for benchmarks and tests without real data.
//
// Shape: ~60 "long" bundles (association pairs mirrored across the midline, projection pairs from a
// brainstem region to the cortex, commissural arcs over the midline) plus 64 short U-fibre bundles just
// under the surface of a brain-sized ellipsoid (semi-axes 70 x 85 x 60 mm, centre (0, -18, 10), RAS mm),
// and five named bundles placed by hand, each a fan of sub-curves from a common stem: the corpus callosum,
// and on each side the corticospinal tract (rising through the callosal fan), cingulum, arcuate fasciculus
// and inferior fronto-occipital fasciculus (listed in the header's "named_bundles"). Seen from the front
// (`voxview --view coronal`) they make the picture in which sorted transparency visibly matters.
// Every bundle has a smooth centre curve (a cubic Bezier with bounded curvature, resampled at 1 mm of
// arc length); every streamline is a random sub-range of one centre curve, displaced inside a tube of a
// few mm whose offset wanders smoothly along the curve, and randomly reversed. Steps are about 1 mm
// (0.75..1.25 mm); long streamlines have 20 + Gamma(2, 21) points, bounded by the longest bundle
// (~165..180 points), U-fibres 20..~40 points: mean ~56.5 points per streamline over seeds 1..100 (HCP's
// 1M set: 56.24). All points lie inside the ellipsoid itself (within ~0.93 of its semi-axes).
//
// Determinism: the output depends only on (streamlines, seed), never on the thread count, standard
// library or libm. Random numbers come from our own splitmix64 and an exact integer->double conversion;
// geometry uses only + - * / and sqrt (IEEE correctly rounded) and our own log, so results are
// bit-identical on any IEEE-754 platform as long as the compiler does not contract a*b+c into FMA
// (every source is compiled with -ffp-contract=off; the generator's also turn it off themselves) and does not
// use x87 excess precision (32-bit x86 without SSE2). Two random draws never share one expression
// (operands of + are unsequenced: GCC and Clang take them in opposite orders).
//
// Prefix property: streamline i depends only on (seed, i) (the bundle layout depends only on seed), so
// the first K streamlines of a set of N >= K are exactly the K streamlines of a set of K.
#pragma once

#include <array>
#include <cstdint>

#include "converter/synth/synth_ellipsoid.h"
#include "converter/tractogram.h"

namespace vxl {

struct SynthSettings {
  std::uint64_t streamlines = 10000;
  std::uint64_t seed = 1;
  unsigned threads = 0;  // worker threads, 0 = hardware concurrency; the output does not depend on it
};

// Bumped whenever the output for a given (streamlines, seed) changes.
inline constexpr int kSynthGeneratorVersion = 2;

// Every point p satisfies sum(((p - centre) / (semi_axes * kSynthEnlarge))^2) <= 1. By construction the
// points stay inside the ellipsoid itself; the generator clamps to this enlarged one as a last guard.
inline constexpr double kSynthEnlarge = 1.02;
inline constexpr std::uint32_t kSynthMinPoints = 20;
inline constexpr std::uint32_t kSynthMaxPoints = 200;

// Fills positions/offsets (float32, exactly sized, no reallocation) and SourceInfo (format "synth",
// dtype "float32", header {"generator", "version", "streamlines", "seed", ...}); path, bytes and
// xxh3_128 are left empty.
Tractogram synthesize_tractogram(const SynthSettings& settings);

}  // namespace vxl
