#include "converter/synth/synth.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "converter/synth/synth_layout.h"
#include "format/base/parallel.h"

#if defined(__linux__)
#include <sys/mman.h>
#endif

// Keep a*b+c as two roundings everywhere (see synth.h, "Determinism"); synth_random.h says why for each compiler.
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

namespace vxl {
namespace {

using namespace synth;

struct Plan {
  std::uint32_t bundle;
  std::uint32_t points;
  double s0;  // start, in samples (mm of arc) along the centre curve
  bool reverse;
};

Rng streamline_rng(std::uint64_t key, std::uint64_t i) { return Rng(mix64(key ^ (i * 0xD1B54A32D192ED03ULL))); }

Plan plan_streamline(const Layout& layout, Rng& rng) {
  Plan plan{};
  if (rng.uniform() < kUFraction) {
    plan.bundle = pick(rng, layout.u_ids, layout.u_cum, 0);
    const std::uint32_t n = layout.bundles[plan.bundle].count();
    plan.points = kSynthMinPoints + static_cast<std::uint32_t>(rng.uniform() * (n - kSynthMinPoints + 1));
    plan.points = std::min(plan.points, n);
  } else {
    const std::uint32_t cap = std::min(layout.max_long_points, kSynthMaxPoints);
    std::uint32_t points = cap;
    for (int tries = 0; tries < 32; ++tries) {
      const double g = kLengthTheta * (rng.exponential() + rng.exponential());  // Gamma(2, theta)
      if (g < static_cast<double>(cap - kSynthMinPoints + 1)) {
        points = kSynthMinPoints + static_cast<std::uint32_t>(g);
        break;
      }
    }
    plan.points = points;
    const auto first = static_cast<std::size_t>(
        std::lower_bound(layout.long_counts.begin(), layout.long_counts.end(), points) - layout.long_counts.begin());
    plan.bundle = pick(rng, layout.long_ids, layout.long_cum, first);
  }
  const std::uint32_t n = layout.bundles[plan.bundle].count();
  plan.s0 = rng.uniform() * static_cast<double>(n - plan.points);  // [0, n - points)
  plan.reverse = (rng.next() >> 63) != 0;
  return plan;
}

// Smoothstep weights for the positions between two wander knots.
struct Smoothstep {
  double h[kWanderKnotSpacing];
  Smoothstep() {
    for (std::uint32_t k = 0; k < kWanderKnotSpacing; ++k) {
      const double t = static_cast<double>(k) / kWanderKnotSpacing;
      h[k] = t * t * (3.0 - 2.0 * t);
    }
  }
};

void generate_streamline(const Layout& layout, const Smoothstep& smooth, const Plan& plan, Rng& rng, float* out) {
  const Bundle& bundle = layout.bundles[plan.bundle];
  const std::uint32_t L = plan.points;
  double a0, b0;
  do {
    a0 = rng.uniform(-1.0, 1.0);
    b0 = rng.uniform(-1.0, 1.0);
  } while (a0 * a0 + b0 * b0 > 1.0);
  constexpr std::uint32_t kMaxKnots = (kSynthMaxPoints - 1) / kWanderKnotSpacing + 2;
  double ka[kMaxKnots], kb[kMaxKnots];
  const std::uint32_t knots = (L - 1) / kWanderKnotSpacing + 2;
  for (std::uint32_t j = 0; j < knots; ++j) {
    ka[j] = a0 + rng.uniform(-kWander, kWander);
    kb[j] = b0 + rng.uniform(-kWander, kWander);
  }
  const double base = std::floor(plan.s0);
  const double f = plan.s0 - base, g = 1.0 - f;
  const Sample* s = bundle.samples.data() + static_cast<std::size_t>(base);
  const double lim2 = (kSynthEnlarge * (1.0 - 1e-6)) * (kSynthEnlarge * (1.0 - 1e-6));
  float* o = plan.reverse ? out + 3 * static_cast<std::size_t>(L - 1) : out;
  const std::ptrdiff_t stride = plan.reverse ? -3 : 3;
  for (std::uint32_t k = 0; k < L; ++k, ++s, o += stride) {
    const std::uint32_t j = k / kWanderKnotSpacing;
    const double h = smooth.h[k % kWanderKnotSpacing];
    const double r = g * s[0].r + f * s[1].r;
    const double ua = r * (ka[j] + (ka[j + 1] - ka[j]) * h);
    const double ub = r * (kb[j] + (kb[j + 1] - kb[j]) * h);
    auto coord = [&](int d) {
      const double c = g * s[0].c[d] + f * s[1].c[d];
      const double n = g * s[0].n[d] + f * s[1].n[d];
      const double b = g * s[0].b[d] + f * s[1].b[d];
      return c + ua * n + ub * b;
    };
    double x = coord(0), y = coord(1), z = coord(2);
    // Last guard (never taken by construction, see kWander): pull back inside the enlarged ellipsoid.
    const double dx = x - kCentre.x, dy = y - kCentre.y, dz = z - kCentre.z;
    const double q = dx * dx * kInvAxes2[0] + dy * dy * kInvAxes2[1] + dz * dz * kInvAxes2[2];
    if (q > lim2) [[unlikely]] {
      const double sc = std::sqrt(lim2 / q);
      x = kCentre.x + sc * dx;
      y = kCentre.y + sc * dy;
      z = kCentre.z + sc * dz;
    }
    o[0] = static_cast<float>(x);
    o[1] = static_cast<float>(y);
    o[2] = static_cast<float>(z);
  }
}

// Runs body(begin, end) over [0, n) in batches of streamlines on `threads` threads.
template <typename Body>
void parallel_batches(std::uint64_t n, unsigned threads, Body body) {
  constexpr std::uint64_t kBatch = 4096;
  parallel_for((n + kBatch - 1) / kBatch, threads,
               [&](std::uint64_t b, unsigned) { body(b * kBatch, std::min(n, (b + 1) * kBatch)); });
}

}  // namespace

Tractogram synthesize_tractogram(const SynthSettings& settings) {
  const std::uint64_t n = settings.streamlines;
  const unsigned threads = resolve_threads(settings.threads);

  const Layout layout = build_layout(settings.seed);
  const std::uint64_t key = mix64(settings.seed ^ 0x73747265616D2131ULL);  // "stream!1"

  Tractogram t;
  t.source.format = "synth";
  t.source.dtype = "float32";
  t.source.header = {{"generator", "voxlines-synth"},
                     {"version", kSynthGeneratorVersion},
                     {"streamlines", n},
                     {"seed", settings.seed},
                     {"long_bundles", layout.long_bundle_count},
                     {"u_fibre_bundles", layout.u_bundle_count},
                     {"named_bundles", layout.named_bundles},
                     {"ellipsoid_centre_mm", kSynthCentre},
                     {"ellipsoid_semi_axes_mm", kSynthSemiAxes},
                     {"step_mm", 1.0}};

  // Pass 1: every streamline's point count (its plan is cheap to redraw), then exact offsets.
  t.offsets.assign(n + 1, 0);
  parallel_batches(n, threads, [&](std::uint64_t begin, std::uint64_t end) {
    for (std::uint64_t i = begin; i < end; ++i) {
      Rng rng = streamline_rng(key, i);
      t.offsets[i + 1] = plan_streamline(layout, rng).points;
    }
  });
  for (std::uint64_t i = 0; i < n; ++i) t.offsets[i + 1] += t.offsets[i];

  // Pass 2: the points, each streamline straight into its final place. The buffer is allocated once at
  // its exact size; on Linux, transparent huge pages make touching ~700 MB (1M streamlines) several
  // times cheaper than 4 KiB page faults.
  const std::size_t floats = static_cast<std::size_t>(3 * t.offsets[n]);
  t.positions.reserve(floats);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (floats * sizeof(float) >= (std::size_t{8} << 20)) {
    constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
    const auto begin = reinterpret_cast<std::uintptr_t>(t.positions.data());
    const std::uintptr_t first = (begin + kHuge - 1) & ~(kHuge - 1);
    const std::uintptr_t last = (begin + floats * sizeof(float)) & ~(kHuge - 1);
    if (last > first) ::madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);  // a hint only
  }
#endif
  t.positions.resize(floats);
  const Smoothstep smooth;
  parallel_batches(n, threads, [&](std::uint64_t begin, std::uint64_t end) {
    for (std::uint64_t i = begin; i < end; ++i) {
      Rng rng = streamline_rng(key, i);
      const Plan plan = plan_streamline(layout, rng);
      generate_streamline(layout, smooth, plan, rng, t.positions.data() + 3 * t.offsets[i]);
    }
  });
  return t;
}

}  // namespace vxl
