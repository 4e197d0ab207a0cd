#include "converter/synth/synth_layout.h"

#include "converter/synth/synth.h"

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

// Keep a*b+c as two roundings everywhere (see synth.h, "Determinism"); synth_random.h says why for each compiler.
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

namespace vxl::synth {
namespace {

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

constexpr int kAssociationPairs = 16;
constexpr int kLongAssociationPairs = 6;    // of which long, >= kLongClassMinPoints points
constexpr int kArchedAssociationPairs = 3;  // and of those, C-shaped arches >= kArchedMinPoints
constexpr std::uint32_t kLongClassMinPoints = 140;
constexpr std::uint32_t kArchedMinPoints = 165;
constexpr int kProjectionPairs = 10;
constexpr int kCommissural = 8;
constexpr int kUPairs = 32;

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

}  // namespace

Layout build_layout(std::uint64_t seed) {
  LayoutBuilder builder(seed);
  builder.add_association_pairs();
  builder.add_projection_pairs();
  builder.add_commissural();
  builder.add_u_fibre_pairs();
  builder.add_named_bundles();
  return builder.finish();
}

std::uint32_t pick(Rng& rng, const std::vector<std::uint32_t>& ids, const std::vector<double>& cum, std::size_t first) {
  const double lo = cum[first], hi = cum.back();
  const double u = lo + (hi - lo) * rng.uniform();
  auto it = std::upper_bound(cum.begin() + static_cast<std::ptrdiff_t>(first) + 1, cum.end(), u);
  std::size_t k = static_cast<std::size_t>(it - cum.begin()) - 1;
  return ids[std::min(k, ids.size() - 1)];
}

}  // namespace vxl::synth
