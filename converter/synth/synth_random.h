// The synthetic generator's arithmetic (synth.cpp, synth_layout.cpp): its random numbers (splitmix64, our own
// double conversion and log, so that every platform draws the same), small vector maths and the brain
// ellipsoid. Internal to the generator.
#pragma once

#include <cmath>
#include <cstdint>

#include "converter/synth/synth_ellipsoid.h"

// Keep a*b+c as two roundings everywhere (see synth.h, "Determinism"). GCC in ISO mode does not contract
// by default and ignores this pragma; Clang contracts by default and honours it.
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

namespace vxl::synth {

// ---- random numbers: splitmix64, our own double conversion ------------------------------------------

inline constexpr std::uint64_t kGolden = 0x9E3779B97F4A7C15ULL;

constexpr std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

class Rng {
 public:
  explicit Rng(std::uint64_t state) : state_(state) {}
  std::uint64_t next() {
    state_ += kGolden;
    return mix64(state_);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1), exact
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Exponential(1) by inversion, with our own log.
  double exponential();

 private:
  std::uint64_t state_;
};

// Natural log from + - * / only (frexp is exact), so it is the same everywhere. Relative error ~1e-16.
inline double det_log(double x) {
  int e = 0;
  double m = std::frexp(x, &e);  // x = m * 2^e, m in [0.5, 1)
  if (m < 0.70710678118654752440) {
    m *= 2.0;
    --e;
  }
  const double f = (m - 1.0) / (m + 1.0);  // |f| <= 0.1716
  const double f2 = f * f;
  const double series =
      f2 *
      (1.0 / 3 +
       f2 * (1.0 / 5 +
             f2 * (1.0 / 7 +
                   f2 * (1.0 / 9 +
                         f2 * (1.0 / 11 + f2 * (1.0 / 13 + f2 * (1.0 / 15 + f2 * (1.0 / 17 + f2 * (1.0 / 19)))))))));
  return 2.0 * (f + f * series) + static_cast<double>(e) * 0.69314718055994530942;
}

inline double Rng::exponential() { return -det_log(1.0 - uniform()); }  // argument in (0, 1]

// ---- small vector maths -------------------------------------------------------------------------------

struct V3 {
  double x = 0, y = 0, z = 0;
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double norm(V3 a) { return std::sqrt(dot(a, a)); }
inline V3 normalized(V3 a) {
  const double n = norm(a);
  return n > 0 ? (1.0 / n) * a : V3{1, 0, 0};
}
inline V3 lerp(V3 a, V3 b, double t) { return a + t * (b - a); }

inline const V3 kCentre{kSynthCentre[0], kSynthCentre[1], kSynthCentre[2]};
inline const V3 kAxes{kSynthSemiAxes[0], kSynthSemiAxes[1], kSynthSemiAxes[2]};

// Squared "ellipsoid radius": 1 on the brain ellipsoid's surface, s^2 on the surface scaled by s.
inline double ellipsoid_q(V3 p) {
  const V3 d = p - kCentre;
  const double x = d.x / kAxes.x, y = d.y / kAxes.y, z = d.z / kAxes.z;
  return x * x + y * y + z * z;
}
// 1 / semi_axis^2, for the per-point guard (multiplications instead of divisions).
inline constexpr double kInvAxes2[3] = {1.0 / (kSynthSemiAxes[0] * kSynthSemiAxes[0]),
                                        1.0 / (kSynthSemiAxes[1] * kSynthSemiAxes[1]),
                                        1.0 / (kSynthSemiAxes[2] * kSynthSemiAxes[2])};
inline bool inside(V3 p, double scale) { return ellipsoid_q(p) <= scale * scale; }

// Uniform point in the brain ellipsoid scaled by `scale`.
inline V3 point_in_ellipsoid(Rng& rng, double scale) {
  for (;;) {
    const V3 u{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    if (dot(u, u) <= 1.0) return kCentre + scale * V3{u.x * kAxes.x, u.y * kAxes.y, u.z * kAxes.z};
  }
}

inline V3 random_unit(Rng& rng) {
  for (;;) {
    const V3 u{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    const double n2 = dot(u, u);
    if (n2 <= 1.0 && n2 > 1e-4) return (1.0 / std::sqrt(n2)) * u;
  }
}

// Random vector perpendicular to `axis` (unit), of length up to `max_len`.
inline V3 random_perpendicular(Rng& rng, V3 axis, double max_len) {
  const V3 u = random_unit(rng);
  return (max_len * rng.uniform()) * normalized(u - dot(u, axis) * axis);
}

}  // namespace vxl::synth
