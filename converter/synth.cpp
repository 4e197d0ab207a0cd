#include "converter/synth.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "format/base/parallel.h"

#if defined(__linux__)
#include <sys/mman.h>
#endif

// Keep a*b+c as two roundings everywhere in this file (see synth.h, "Determinism"). GCC in ISO mode
// does not contract by default and ignores this pragma; Clang contracts by default and honours it.
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

namespace vxl {
namespace {

// ---- random numbers: splitmix64, our own double conversion ------------------------------------------

constexpr std::uint64_t kGolden = 0x9E3779B97F4A7C15ULL;

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
double det_log(double x) {
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

double Rng::exponential() { return -det_log(1.0 - uniform()); }  // argument in (0, 1]

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

const V3 kCentre{kSynthCentre[0], kSynthCentre[1], kSynthCentre[2]};
const V3 kAxes{kSynthSemiAxes[0], kSynthSemiAxes[1], kSynthSemiAxes[2]};

// Squared "ellipsoid radius": 1 on the brain ellipsoid's surface, s^2 on the surface scaled by s.
inline double ellipsoid_q(V3 p) {
  const V3 d = p - kCentre;
  const double x = d.x / kAxes.x, y = d.y / kAxes.y, z = d.z / kAxes.z;
  return x * x + y * y + z * z;
}
// 1 / semi_axis^2, for the per-point guard (multiplications instead of divisions).
constexpr double kInvAxes2[3] = {1.0 / (kSynthSemiAxes[0] * kSynthSemiAxes[0]),
                                 1.0 / (kSynthSemiAxes[1] * kSynthSemiAxes[1]),
                                 1.0 / (kSynthSemiAxes[2] * kSynthSemiAxes[2])};
inline bool inside(V3 p, double scale) { return ellipsoid_q(p) <= scale * scale; }

// Uniform point in the brain ellipsoid scaled by `scale`.
V3 point_in_ellipsoid(Rng& rng, double scale) {
  for (;;) {
    const V3 u{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    if (dot(u, u) <= 1.0) return kCentre + scale * V3{u.x * kAxes.x, u.y * kAxes.y, u.z * kAxes.z};
  }
}

V3 random_unit(Rng& rng) {
  for (;;) {
    const V3 u{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    const double n2 = dot(u, u);
    if (n2 <= 1.0 && n2 > 1e-4) return (1.0 / std::sqrt(n2)) * u;
  }
}

// Random vector perpendicular to `axis` (unit), of length up to `max_len`.
V3 random_perpendicular(Rng& rng, V3 axis, double max_len) {
  const V3 u = random_unit(rng);
  return (max_len * rng.uniform()) * normalized(u - dot(u, axis) * axis);
}

// ---- bundles ------------------------------------------------------------------------------------------

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

struct BundleSpec {
  V3 p[4];               // Bezier control points, all inside the curve ellipsoid (so the curve is too)
  double radius;         // tube radius in the middle, mm
  double flare;          // radius grows by (1 + flare) towards the ends
  double max_curvature;  // 1/mm
  std::uint32_t min_samples, max_samples;
};

V3 bezier(const V3 p[4], double t) {
  const double s = 1.0 - t;
  const double b0 = s * s * s, b1 = 3.0 * s * s * t, b2 = 3.0 * s * t * t, b3 = t * t * t;
  return b0 * p[0] + b1 * p[1] + b2 * p[2] + b3 * p[3];
}

// Resamples the Bezier at 1 mm of arc length and builds frames and radii. nullopt if the curve is too
// short, too long or too tightly bent.
std::optional<Bundle> build_bundle(const BundleSpec& spec) {
  constexpr int kFine = 2048;
  std::vector<V3> fine(kFine + 1);
  std::vector<double> cum(kFine + 1, 0.0);
  for (int j = 0; j <= kFine; ++j) {
    fine[j] = bezier(spec.p, static_cast<double>(j) / kFine);
    if (j > 0) cum[j] = cum[j - 1] + norm(fine[j] - fine[j - 1]);
  }
  const double length = cum[kFine];
  if (!(length >= 1.0)) return std::nullopt;
  const auto n = static_cast<std::uint32_t>(std::floor(length)) + 1;
  if (n < spec.min_samples || n > spec.max_samples) return std::nullopt;

  std::vector<V3> c(n);
  int j = 0;
  for (std::uint32_t k = 0; k < n; ++k) {
    const double s = static_cast<double>(k);
    while (j + 1 < kFine && cum[j + 1] < s) ++j;
    const double seg = cum[j + 1] - cum[j];
    const double t = seg > 0 ? std::clamp((s - cum[j]) / seg, 0.0, 1.0) : 0.0;
    c[k] = lerp(fine[j], fine[j + 1], t);
  }

  std::vector<V3> tangent(n);
  for (std::uint32_t k = 0; k < n; ++k) tangent[k] = normalized(c[std::min(k + 1, n - 1)] - c[k > 0 ? k - 1 : 0]);
  for (std::uint32_t k = 0; k + 1 < n; ++k) {
    const double step = norm(c[k + 1] - c[k]);
    if (step <= 0 || norm(tangent[k + 1] - tangent[k]) > spec.max_curvature * step) return std::nullopt;
  }

  Bundle bundle;
  bundle.samples.resize(n + 1);
  // Initial normal: perpendicular to the tangent, from the axis least aligned with it.
  const V3 t0 = tangent[0];
  const V3 axis = (std::fabs(t0.x) <= std::fabs(t0.y) && std::fabs(t0.x) <= std::fabs(t0.z)) ? V3{1, 0, 0}
                  : (std::fabs(t0.y) <= std::fabs(t0.z))                                     ? V3{0, 1, 0}
                                                                                             : V3{0, 0, 1};
  V3 nrm = normalized(cross(t0, axis));
  for (std::uint32_t k = 0; k < n; ++k) {
    const V3 t = tangent[k];
    nrm = normalized(nrm - dot(nrm, t) * t);  // projection transport: rotation-minimising at 1 mm steps
    const V3 bin = cross(t, nrm);
    const double w = n > 1 ? 2.0 * k / (n - 1) - 1.0 : 0.0;  // -1 .. 1 along the curve
    const double w2 = w * w;
    Sample& sm = bundle.samples[k];
    sm.c[0] = c[k].x, sm.c[1] = c[k].y, sm.c[2] = c[k].z;
    sm.n[0] = nrm.x, sm.n[1] = nrm.y, sm.n[2] = nrm.z;
    sm.b[0] = bin.x, sm.b[1] = bin.y, sm.b[2] = bin.z;
    sm.r = spec.radius * (1.0 + spec.flare * w2 * w2);
  }
  bundle.samples[n] = bundle.samples[n - 1];
  return bundle;
}

V3 mirror_x(V3 p) { return {2.0 * kCentre.x - p.x, p.y, p.z}; }

BundleSpec mirrored(const BundleSpec& s) {
  BundleSpec m = s;
  for (auto& p : m.p) p = mirror_x(p);
  return m;
}

// Long-bundle geometry.
constexpr double kCurveScale = 0.88;   // long centre curves stay inside the ellipsoid scaled by this
constexpr double kUCurveScale = 0.90;  // U-fibre centre curves likewise
constexpr double kMaxCurvatureLong = 1.0 / 25.0;
constexpr double kMaxCurvatureU = 1.0 / 7.0;
constexpr double kMaxCurvatureNamed = 1.0 / 12.0;  // the arcuate's arch is tighter than a random bundle's
// Offsets: a base point in the unit disc plus a wander of +-kWander per component, times the radius.
// Max offset = radius * (1 + flare) * (1 + kWander * sqrt 2): long <= 3 * 1.4 * 1.36 = 5.7 mm, less than
// the 7.2 mm margin between the 0.88-scaled ellipsoid K and the brain ellipsoid E = K / 0.88 (E = K +
// (1/0.88 - 1) K, and K contains a ball of radius 0.88 * 60 mm, so E contains K + a ball of (1 - 0.88) *
// 60 mm); U-fibres <= 1.4 * 1.2 * 1.36 = 2.3 mm of a 6 mm margin. Interpolated frames are at most unit
// length and within ~0.3% of orthogonal. So every point is inside the brain ellipsoid by construction.
constexpr double kWander = 0.25;
constexpr std::uint32_t kWanderKnotSpacing = 16;  // mm between wander knots (a power of two)

// Smooth bent control points between two ends: thirds of the chord displaced sideways.
BundleSpec bent_curve(Rng& rng, V3 a, V3 b, double bend) {
  BundleSpec spec{};
  const V3 chord = b - a;
  const double len = norm(chord);
  const V3 dir = (1.0 / len) * chord;
  spec.p[0] = a;
  spec.p[1] = a + (1.0 / 3.0) * chord + random_perpendicular(rng, dir, bend * len);
  spec.p[2] = a + (2.0 / 3.0) * chord + random_perpendicular(rng, dir, bend * len);
  spec.p[3] = b;
  return spec;
}

// A C-shaped arch: both thirds of the chord pushed the same way (long fasciculi curving around deep
// structures).
BundleSpec arched_curve(Rng& rng, V3 a, V3 b, double bend) {
  BundleSpec spec{};
  const V3 chord = b - a;
  const double len = norm(chord);
  const V3 dir = (1.0 / len) * chord;
  const V3 u = random_unit(rng);
  const V3 side = normalized(u - dot(u, dir) * dir);
  // One draw per statement: the operands of + are unsequenced, and GCC (right to left) and Clang (left to
  // right) took the two draws of `a + ... + push * side + jitter` in opposite orders. This is GCC's order,
  // the one the pinned outputs were made with.
  for (int k = 1; k <= 2; ++k) {
    const V3 jitter = random_perpendicular(rng, dir, 0.1 * len);
    const double push = bend * len * rng.uniform(0.8, 1.0);
    spec.p[k] = a + (k / 3.0) * chord + push * side + jitter;
  }
  spec.p[0] = a;
  spec.p[3] = b;
  return spec;
}

bool controls_inside(const BundleSpec& spec, double scale) {
  for (const auto& p : spec.p)
    if (!inside(p, scale)) return false;
  return true;
}

void set_long_tube(Rng& rng, BundleSpec& spec) {
  spec.radius = rng.uniform(1.5, 3.0);
  spec.flare = rng.uniform(0.0, 0.4);
  spec.max_curvature = kMaxCurvatureLong;
  spec.min_samples = 40;
  spec.max_samples = kSynthMaxPoints;
}

// Draws until `make` gives a spec whose curve is valid. The constraints are loose enough that this ends
// after a few dozen tries; the cap only guards against a bug.
template <typename Make>
Bundle draw_bundle(Rng& rng, Make make, BundleSpec* spec_out = nullptr) {
  for (int attempt = 0; attempt < 1000000; ++attempt) {
    BundleSpec spec = make();
    if (auto b = build_bundle(spec)) {
      b->weight = 0.3 + rng.uniform();
      if (spec_out) *spec_out = spec;
      return std::move(*b);
    }
  }
  throw std::logic_error("synthesize_tractogram: could not place a bundle");
}

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

constexpr int kAssociationPairs = 16;
constexpr int kLongAssociationPairs = 6;    // of which long, >= kLongClassMinPoints points
constexpr int kArchedAssociationPairs = 3;  // and of those, C-shaped arches >= kArchedMinPoints
constexpr std::uint32_t kLongClassMinPoints = 140;
constexpr std::uint32_t kArchedMinPoints = 165;
constexpr int kProjectionPairs = 10;
constexpr int kCommissural = 8;
constexpr int kUPairs = 32;
constexpr double kUFraction = 0.12;  // share of streamlines that are U-fibres
// Long streamlines have 20 + floor(Gamma(2, kLengthTheta)) points; with 12% U-fibres of ~31 points the
// overall mean is ~56.
constexpr double kLengthTheta = 21.0;

// Named bundles, placed by hand so that a picture shows a few familiar structures running through one
// another (the corticospinal tracts rise through the corpus callosum's fan, the cinguli run above it, the
// arcuate arches around the side): the scene where sorted transparency shows what lies inside. Each is a
// fan of sub-curves from a common stem; left-hemisphere coordinates, mirrored where `mirrored`. `weight`
// is the bundle's share of long streamlines relative to a random bundle's ~0.8.
struct NamedBundle {
  const char* name;
  V3 p0, p1;        // the stem
  V3 p2_a, p2_b;    // the fan's third control point, from one side of the fan to the other
  V3 end_a, end_b;  // the fanning ends
  int fan;
  double radius;
  double weight;
  bool mirrored;
};
const NamedBundle kNamedBundles[] = {
    {"corpus callosum",
     {-42, -5, 38},
     {-14, -12, 34},
     {14, -35, 34},
     {14, 20, 34},
     {42, -45, 38},
     {42, 25, 38},
     9,
     2.5,
     14.0,
     false},
    {"corticospinal tract",
     {-8, -24, -36},
     {-14, -16, -2},
     {-20, -34, 30},
     {-28, -4, 30},
     {-16, -40, 55},
     {-42, -8, 42},
     7,
     2.5,
     7.0,
     true},
    {"cingulum",
     {-7, 30, 8},
     {-8, 28, 38},
     {-8, -35, 40},
     {-8, -35, 40},
     {-9, -62, 12},
     {-9, -62, 12},
     1,
     3.0,
     3.0,
     true},
    {"arcuate fasciculus",
     {-40, 18, 18},
     {-40, -50, 34},
     {-48, -52, -6},
     {-48, -52, -6},
     {-48, -5, -16},
     {-48, -5, -16},
     1,
     3.0,
     3.0,
     true},
    {"inferior fronto-occipital fasciculus",
     {-20, 44, 4},
     {-32, 5, -8},
     {-34, -45, -4},
     {-34, -45, -4},
     {-22, -82, 6},
     {-22, -82, 6},
     1,
     3.0,
     3.0,
     true},
};

// Builds the layout bundle class by bundle class, drawing from one random stream in a fixed order.
class LayoutBuilder {
 public:
  explicit LayoutBuilder(std::uint64_t seed) : rng_(mix64(seed ^ 0x6C61796F75742131ULL)) {}  // "layout!1"

  void add_association_pairs();
  void add_projection_pairs();
  void add_commissural();
  void add_u_fibre_pairs();
  void add_named_bundles();
  Layout finish();

 private:
  // A long bundle and its mirror image in the right hemisphere (same shape, so equally valid).
  template <typename Make>
  void add_pair(Make make) {
    BundleSpec spec;
    longs_.push_back(draw_bundle(rng_, make, &spec));
    add_mirror(longs_, spec);
  }
  void add_mirror(std::vector<Bundle>& into, const BundleSpec& spec) {
    Bundle mirror = *build_bundle(mirrored(spec));
    mirror.weight = 0.3 + rng_.uniform();
    into.push_back(std::move(mirror));
  }
  // A cortical end: in the outer shell of the curve ellipsoid, left hemisphere.
  V3 cortical(double min_abs_x) {
    for (;;) {
      const V3 p = point_in_ellipsoid(rng_, kCurveScale);
      if (p.x <= -min_abs_x && ellipsoid_q(p) >= 0.6 * 0.6) return p;
    }
  }
  void add_fan(const NamedBundle& named, bool mirror);

  Rng rng_;
  std::vector<Bundle> longs_, us_;
  std::vector<std::string> names_;
};

// Association: both ends in the left hemisphere (the pair's mirror is on the right); the first few are
// long, mostly anterior-posterior fasciculi.
void LayoutBuilder::add_association_pairs() {
  for (int i = 0; i < kAssociationPairs; ++i) {
    const bool arched = i < kArchedAssociationPairs;
    const bool long_class = i < kLongAssociationPairs;
    const double min_chord = arched ? 70.0 : long_class ? 90.0 : 50.0;
    const double max_chord = arched ? 130.0 : long_class ? 165.0 : 140.0;
    const double min_bend = arched ? 0.5 : long_class ? 0.25 : 0.1;
    const double max_bend = arched ? 0.9 : long_class ? 0.6 : 0.4;
    const std::uint32_t min_points = arched ? kArchedMinPoints : kLongClassMinPoints;
    add_pair([&] {
      for (;;) {
        const V3 a = cortical(12.0), b = cortical(12.0);
        const double chord = norm(b - a);
        if (chord < min_chord || chord > max_chord) continue;
        const double bend = rng_.uniform(min_bend, max_bend);
        BundleSpec spec = arched ? arched_curve(rng_, a, b, bend) : bent_curve(rng_, a, b, bend);
        if (!controls_inside(spec, kCurveScale)) continue;
        set_long_tube(rng_, spec);
        if (long_class) {
          spec.min_samples = min_points;
          // The control polygon bounds the arc length from above: skip hopeless candidates cheaply.
          if (norm(spec.p[1] - spec.p[0]) + norm(spec.p[2] - spec.p[1]) + norm(spec.p[3] - spec.p[2]) < min_points)
            continue;
        }
        return spec;
      }
    });
  }
}

// Projection: from a brainstem / internal-capsule region up to the cortex of the same hemisphere.
void LayoutBuilder::add_projection_pairs() {
  for (int i = 0; i < kProjectionPairs; ++i) {
    add_pair([&] {
      for (;;) {
        const V3 a{-rng_.uniform(3.0, 12.0), rng_.uniform(-30.0, -12.0), rng_.uniform(-42.0, -28.0)};
        const V3 b = cortical(15.0);
        if (b.z < 5.0 || norm(b - a) < 70.0) continue;
        BundleSpec spec = bent_curve(rng_, a, b, rng_.uniform(0.1, 0.3));
        if (!controls_inside(spec, kCurveScale)) continue;
        set_long_tube(rng_, spec);
        return spec;
      }
    });
  }
}

// Commissural: left cortex, arching over the midline above the ventricles, to the right cortex.
void LayoutBuilder::add_commissural() {
  for (int i = 0; i < kCommissural; ++i) {
    longs_.push_back(draw_bundle(rng_, [&] {
      for (;;) {
        const V3 a = cortical(30.0);
        if (a.z < 0.0) continue;
        const V3 b{-a.x + rng_.uniform(-8.0, 8.0), a.y + rng_.uniform(-15.0, 15.0), a.z + rng_.uniform(-10.0, 10.0)};
        const double ym = 0.5 * (a.y + b.y) + rng_.uniform(-10.0, 10.0);
        const double zc = std::max(a.z, b.z) + rng_.uniform(5.0, 25.0);
        BundleSpec spec{};
        spec.p[0] = a;
        spec.p[1] = {-rng_.uniform(8.0, 20.0), ym + rng_.uniform(-5.0, 5.0), zc + rng_.uniform(-3.0, 3.0)};
        spec.p[2] = {rng_.uniform(8.0, 20.0), ym + rng_.uniform(-5.0, 5.0), zc + rng_.uniform(-3.0, 3.0)};
        spec.p[3] = b;
        if (!controls_inside(spec, kCurveScale)) continue;
        set_long_tube(rng_, spec);
        return spec;
      }
    }));
  }
}

// U-fibres: short arcs dipping under the surface between two nearby points of the (scaled) surface, kept
// to the cerebrum (not the inferior surface).
void LayoutBuilder::add_u_fibre_pairs() {
  for (int i = 0; i < kUPairs; ++i) {
    BundleSpec spec;
    us_.push_back(draw_bundle(
        rng_,
        [&] {
          for (;;) {
            const V3 d = random_unit(rng_);
            if (d.z < -0.3 || d.x > -0.1) continue;  // left hemisphere; the mirror covers the right
            auto to_surface = [](V3 p) { return kCentre + (kUCurveScale / std::sqrt(ellipsoid_q(p))) * (p - kCentre); };
            const V3 a = to_surface(kCentre + V3{d.x * kAxes.x, d.y * kAxes.y, d.z * kAxes.z});
            const V3 inward0 = normalized(kCentre - a);
            const V3 u = random_unit(rng_);
            const V3 side = normalized(u - dot(u, inward0) * inward0);
            const V3 b = to_surface(a + rng_.uniform(14.0, 26.0) * side);
            const V3 mid = 0.5 * (a + b);
            const V3 g = mid - kCentre;  // ellipsoid normal at mid: gradient of q
            const V3 inward =
                -1.0 * normalized(V3{g.x / (kAxes.x * kAxes.x), g.y / (kAxes.y * kAxes.y), g.z / (kAxes.z * kAxes.z)});
            const double depth = rng_.uniform(8.0, 14.0);
            BundleSpec s{};
            s.p[0] = a;
            s.p[1] = a + depth * inward;
            s.p[2] = b + depth * inward;
            s.p[3] = b;
            if (!controls_inside(s, kUCurveScale + 1e-9)) continue;
            s.radius = rng_.uniform(0.8, 1.4);
            s.flare = rng_.uniform(0.0, 0.2);
            s.max_curvature = kMaxCurvatureU;
            s.min_samples = kSynthMinPoints + 4;
            s.max_samples = 60;
            return s;
          }
        },
        &spec));
    add_mirror(us_, spec);
  }
}

// One named bundle: `fan` sub-curves from a common stem (p0, p1) whose far ends (p2, p3) spread from
// `end_a` to `end_b` (the fanning ends of real bundles), each control point jittered a little.
void LayoutBuilder::add_fan(const NamedBundle& named, bool mirror) {
  for (int k = 0; k < named.fan; ++k) {
    const double t = named.fan > 1 ? static_cast<double>(k) / (named.fan - 1) : 0.5;
    BundleSpec spec;
    Bundle b = draw_bundle(
        rng_,
        [&] {
          for (;;) {
            BundleSpec s{};
            s.p[0] = named.p0 + V3{rng_.uniform(-2, 2), rng_.uniform(-2, 2), rng_.uniform(-2, 2)};
            s.p[1] = named.p1 + V3{rng_.uniform(-3, 3), rng_.uniform(-3, 3), rng_.uniform(-3, 3)};
            s.p[2] =
                lerp(named.p2_a, named.p2_b, t) + V3{rng_.uniform(-3, 3), rng_.uniform(-3, 3), rng_.uniform(-3, 3)};
            s.p[3] =
                lerp(named.end_a, named.end_b, t) + V3{rng_.uniform(-3, 3), rng_.uniform(-3, 3), rng_.uniform(-3, 3)};
            if (!controls_inside(s, kCurveScale)) continue;
            set_long_tube(rng_, s);
            s.radius = named.radius;
            s.flare = 0.3;
            s.max_curvature = kMaxCurvatureNamed;
            return s;
          }
        },
        &spec);
    b.weight = named.weight / named.fan;
    longs_.push_back(std::move(b));
    if (mirror) {
      add_mirror(longs_, spec);
      longs_.back().weight = named.weight / named.fan;
    }
  }
  names_.push_back(named.name);
}

void LayoutBuilder::add_named_bundles() {
  for (const NamedBundle& named : kNamedBundles) add_fan(named, named.mirrored);
}

Layout LayoutBuilder::finish() {
  Layout layout;
  layout.long_bundle_count = longs_.size();
  layout.u_bundle_count = us_.size();
  layout.named_bundles = std::move(names_);
  for (auto& b : longs_) layout.bundles.push_back(std::move(b));
  for (auto& b : us_) layout.bundles.push_back(std::move(b));

  for (std::uint32_t i = 0; i < layout.long_bundle_count; ++i) layout.long_ids.push_back(i);
  std::stable_sort(layout.long_ids.begin(), layout.long_ids.end(), [&](std::uint32_t a, std::uint32_t b) {
    return layout.bundles[a].count() < layout.bundles[b].count();
  });
  layout.long_cum.push_back(0.0);
  for (auto id : layout.long_ids) {
    layout.long_counts.push_back(layout.bundles[id].count());
    layout.long_cum.push_back(layout.long_cum.back() + layout.bundles[id].weight);
  }
  layout.max_long_points = layout.long_counts.back();
  layout.u_cum.push_back(0.0);
  for (std::uint32_t i = 0; i < layout.u_bundle_count; ++i) {
    const auto id = static_cast<std::uint32_t>(layout.long_bundle_count + i);
    layout.u_ids.push_back(id);
    layout.u_cum.push_back(layout.u_cum.back() + layout.bundles[id].weight);
  }
  return layout;
}

Layout build_layout(std::uint64_t seed) {
  LayoutBuilder builder(seed);
  builder.add_association_pairs();
  builder.add_projection_pairs();
  builder.add_commissural();
  builder.add_u_fibre_pairs();
  builder.add_named_bundles();
  return builder.finish();
}

// Weighted pick among ids[first..] with cumulative weights cum (size ids.size() + 1).
std::uint32_t pick(Rng& rng, const std::vector<std::uint32_t>& ids, const std::vector<double>& cum, std::size_t first) {
  const double lo = cum[first], hi = cum.back();
  const double u = lo + (hi - lo) * rng.uniform();
  auto it = std::upper_bound(cum.begin() + static_cast<std::ptrdiff_t>(first) + 1, cum.end(), u);
  std::size_t k = static_cast<std::size_t>(it - cum.begin()) - 1;
  return ids[std::min(k, ids.size() - 1)];
}

// ---- streamlines --------------------------------------------------------------------------------------

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
