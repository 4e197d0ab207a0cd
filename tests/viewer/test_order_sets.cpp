// Order sets (axis, axis+diag, random:N): the renderer's choice of stored order is the signed direction
// nearest to the view direction among the voxel's own 2K candidates (spec §6.4), per-voxel directions
// travel through the file (VDIR, spec §5.10), and the order hysteresis keeps or switches as documented.
// CPU only: SceneLayout and plan_frame need no GL context.
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>

#include <glm/glm.hpp>

#include "converter/convert/convert.h"
#include "converter/convert/segment_orders.h"
#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_verify.h"
#include "tests/test_support.h"
#include "viewer/render/camera.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/scene_layout.h"

namespace vxl {
namespace {

using test::ScratchDir;

const char* const kOrderSets[] = {"axis", "axis+diag", "random:1", "random:5", "random:16", "random:64"};

// Reproducible pseudo-random unit vectors (not the converter's generator: an independent source).
struct TestRng {
  std::uint64_t s;
  double uniform() {  // [0, 1), xorshift64*
    s ^= s >> 12, s ^= s << 25, s ^= s >> 27;
    return double((s * 0x2545F4914F6CDD1Dull) >> 11) * 0x1.0p-53;
  }
  glm::dvec3 direction() {
    for (;;) {
      glm::dvec3 p(2 * uniform() - 1, 2 * uniform() - 1, 2 * uniform() - 1);
      double r = glm::length(p);
      if (r > 1e-3 && r <= 1) return p / r;
    }
  }
};

// The signed direction a choice serves, and the best score over all 2K candidates.
glm::dvec3 served(std::span<const glm::vec3> dirs, std::uint32_t slot, bool reversed) {
  return reversed ? -glm::dvec3(dirs[slot]) : glm::dvec3(dirs[slot]);
}
double best_score(std::span<const glm::vec3> dirs, const glm::dvec3& w) {
  double best = -2;
  for (const glm::vec3& d : dirs)
    for (double sign : {1.0, -1.0}) best = std::max(best, glm::dot(sign * glm::dvec3(d), -w));
  return best;
}

std::vector<glm::vec3> to_vec3(std::span<const std::array<float, 3>> dirs) {
  std::vector<glm::vec3> out;
  for (const auto& d : dirs) out.push_back({d[0], d[1], d[2]});
  return out;
}

TEST(OrderSets, NearestOrderMaximisesTheDotProductOverAllSignedDirections) {
  TestRng rng{42};
  for (const char* name : kOrderSets) {
    OrderSetSpec set = parse_order_set(name);
    for (int voxel = 0; voxel < 20; ++voxel) {
      const std::int32_t coord[3] = {voxel, 3 * voxel % 7, 100 - voxel};
      std::vector<std::array<float, 3>> raw(set.directions.size());
      voxel_directions(set, coord, raw);
      const std::vector<glm::vec3> dirs = to_vec3(raw);
      for (int i = 0; i < 200; ++i) {
        const glm::dvec3 w = rng.direction();
        auto [slot, reversed] = nearest_order(dirs, w);
        ASSERT_LT(slot, dirs.size());
        // Back to front for an eye looking along w: the served direction points against w.
        EXPECT_NEAR(glm::dot(served(dirs, slot, reversed), -w), best_score(dirs, w), 1e-6) << name;
        EXPECT_DOUBLE_EQ(order_alignment(dirs, slot, reversed, w), glm::dot(served(dirs, slot, reversed), -w));
      }
    }
  }
}

TEST(OrderSets, AxisViewsPickTheMatchingAxisOrder) {
  const std::vector<glm::vec3> axis = to_vec3(parse_order_set("axis").directions);
  // Looking along -X (eye on the +X side) is served by +X read forwards; along +X by +X read backwards.
  EXPECT_EQ(nearest_order(axis, {-1, 0, 0}), std::make_pair(0u, false));
  EXPECT_EQ(nearest_order(axis, {1, 0, 0}), std::make_pair(0u, true));
  EXPECT_EQ(nearest_order(axis, {0, 0.1, -0.9}), std::make_pair(2u, false));
}

TEST(OrderSets, RandomDirectionsAreUnitDeterministicAndDifferPerVoxel) {
  OrderSetSpec set = parse_order_set("random:16");
  EXPECT_EQ(set.kind, OrderSet::Random);
  EXPECT_EQ(set.directions.size(), 16u);
  std::vector<std::array<float, 3>> a(16), b(16), c(16);
  const std::int32_t v0[3] = {4, 5, 6}, v1[3] = {5, 5, 6};
  voxel_directions(set, v0, a);
  voxel_directions(set, v0, b);
  voxel_directions(set, v1, c);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  // Uniform on the sphere: over many voxels the mean is near 0 and each |component| averages 1/2.
  glm::dvec3 sum(0.0), abs_sum(0.0);
  int n = 0;
  for (std::int32_t x = 0; x < 20; ++x)
    for (std::int32_t y = 0; y < 20; ++y) {
      const std::int32_t v[3] = {x, y, 7};
      voxel_directions(set, v, a);
      for (const auto& d : a) {
        glm::dvec3 p(d[0], d[1], d[2]);
        EXPECT_NEAR(glm::length(p), 1.0, 1e-6);
        sum += p;
        abs_sum += glm::abs(p);
        ++n;
      }
    }
  for (int c2 = 0; c2 < 3; ++c2) {
    EXPECT_NEAR(sum[c2] / n, 0.0, 0.03);
    EXPECT_NEAR(abs_sum[c2] / n, 0.5, 0.02);
  }
  EXPECT_THROW(parse_order_set("random:0"), Error);
  EXPECT_THROW(parse_order_set("random:65"), Error);
  EXPECT_THROW(parse_order_set("random:x"), Error);
}

// A small synthetic brain converted with `orders`.
VxlFile convert_synth(const ScratchDir& dir, const std::string& orders, double voxel_size, const std::string& name) {
  SynthSettings s;
  s.streamlines = 300;
  s.seed = 5;
  ConvertSettings c;
  c.voxel_size = voxel_size;
  c.orders = orders;
  c.threads = 2;
  convert_tractogram(synthesize_tractogram(s), dir.file(name), c);
  return VxlFile::open(dir.file(name));
}

// Decodes which {slot, reversed} each planned voxel is drawn with.
std::pair<std::uint32_t, bool> planned_order(const SceneLayout& layout, std::uint32_t voxel, std::int32_t first) {
  for (std::uint32_t slot = 0; slot < layout.stored_orders(); ++slot)
    for (bool reversed : {false, true})
      if (layout.first_id(layout.voxels()[voxel], slot, reversed) == first) return {slot, reversed};
  ADD_FAILURE() << "voxel " << voxel << " is not drawn in a stored order";
  return {0, false};
}

ViewParams view_of(const Camera& cam) {
  glm::dmat4 projection(cam.projection(1.0, cam.orthographic ? -1e4 : 1.0, 1e4));
  return make_view_params(cam.eye(), cam.forward(), cam.orthographic, projection, glm::dmat3(cam.view_rotation()));
}

TEST(OrderSets, EveryPlannedVoxelUsesItsNearestOwnDirection) {
  ScratchDir dir;
  TestRng rng{7};
  for (const char* name : kOrderSets) {
    VxlFile f = convert_synth(dir, name, 12.0, "scene.vxl");
    SceneLayout layout(f, 1u << 30);
    ASSERT_EQ(layout.stored_orders(), parse_order_set(name).directions.size());
    FramePlan plan;
    for (int view = 0; view < 12; ++view) {
      Camera cam;
      cam.orthographic = view % 3 == 0;
      cam.azimuth_deg = 360 * rng.uniform();
      cam.elevation_deg = 180 * rng.uniform() - 90;
      cam.frame({-80, -110, -60}, {80, 80, 80}, 1.0);
      ViewParams v = view_of(cam);
      plan_frame(layout, v, PlanOrder::Nearest, plan);
      ASSERT_GT(plan.first.size(), 10u) << name;
      for (std::size_t j = 0; j < plan.first.size(); ++j) {
        const std::uint32_t i = plan.sort_keys[j].second;
        // The file's directions for this voxel, as stored (VDIR or DIRS).
        std::vector<glm::vec3> dirs;
        for (const DirectionEntry& d : f.directions_of(i)) dirs.push_back({d.xyz[0], d.xyz[1], d.xyz[2]});
        const glm::dvec3 w = cam.orthographic ? v.forward : glm::normalize(layout.voxels()[i].center - v.eye);
        auto [slot, reversed] = planned_order(layout, i, plan.first[j]);
        EXPECT_NEAR(glm::dot(served(dirs, slot, reversed), -w), best_score(dirs, w), 1e-6) << name << " voxel " << i;
      }
    }
  }
}

TEST(VisibilityOrder, NoVoxelComesAfterOneItHides) {
  // For every two face neighbours among the planned voxels, the one across the shared face from the eye
  // must come first. Perspective views from outside and from inside the grid, and orthographic ones.
  ScratchDir dir;
  VxlFile f = convert_synth(dir, "axis", 12.0, "scene.vxl");
  SceneLayout layout(f, 1u << 30);
  const double s = f.meta().voxel_size;
  TestRng rng{11};
  FramePlan plan;
  int pairs = 0;
  for (int view = 0; view < 12; ++view) {
    Camera cam;
    cam.orthographic = view % 4 == 0;
    cam.azimuth_deg = 360 * rng.uniform();
    cam.elevation_deg = 180 * rng.uniform() - 90;
    cam.frame({-80, -110, -60}, {80, 80, 80}, 1.0);
    if (view % 4 == 1) cam.distance = 30;  // the eye among the voxels
    const ViewParams v = view_of(cam);
    plan_frame(layout, v, PlanOrder::Visibility, plan);
    ASSERT_GT(plan.first.size(), 10u);
    std::map<std::array<long, 3>, std::size_t> position;  // voxel cell (i, j, k) -> place in the plan
    const double* origin = f.meta().grid_origin;
    for (std::size_t j = 0; j < plan.sort_keys.size(); ++j) {
      const glm::dvec3 c = layout.voxels()[plan.sort_keys[j].second].center;
      position[{std::lround((c.x - origin[0]) / s - 0.5), std::lround((c.y - origin[1]) / s - 0.5),
                std::lround((c.z - origin[2]) / s - 0.5)}] = j;
    }
    for (const auto& [cell, j] : position)
      for (int axis = 0; axis < 3; ++axis) {
        std::array<long, 3> next = cell;
        ++next[axis];
        auto it = position.find(next);
        if (it == position.end()) continue;
        const double face = origin[axis] + double(cell[axis] + 1) * s;  // the shared face's coordinate
        const double eye = v.orthographic ? -v.forward[axis] * 1e9 : v.eye[axis];
        if (std::abs(eye - face) < 1e-9) continue;  // the eye in the face's plane: either order is right
        ++pairs;
        if (eye < face)
          EXPECT_LT(it->second, j) << "the voxel beyond the face from the eye must come first";
        else
          EXPECT_LT(j, it->second) << "the voxel beyond the face from the eye must come first";
      }
  }
  EXPECT_GT(pairs, 1000);
}

TEST(OrderSets, RandomFilesCarryRequiredPerVoxelDirectionsAndVerify) {
  ScratchDir dir;
  VxlFile axis = convert_synth(dir, "axis", 10.0, "axis.vxl");
  EXPECT_EQ(axis.header().version_major, 2);  // levels of detail (the default)
  EXPECT_EQ(axis.header().version_minor, 4);
  EXPECT_EQ(axis.find_section(section_id("VDIR")), nullptr);
  EXPECT_TRUE(axis.voxel_directions().empty());

  VxlFile r = convert_synth(dir, "random:8", 10.0, "random.vxl");
  EXPECT_EQ(r.header().version_major, 2);  // 2.4 holds VDIR too (1.5 with float32 positions and one level)
  EXPECT_EQ(r.header().version_minor, 4);
  EXPECT_EQ(r.meta().order_set, static_cast<std::uint32_t>(OrderSet::Random));
  EXPECT_EQ(r.meta().stored_order_count, 8u);
  const SectionEntry* vdir = r.find_section(section_id("VDIR"));
  ASSERT_NE(vdir, nullptr);
  EXPECT_EQ(vdir->flags & kSectionRequired, kSectionRequired);
  EXPECT_EQ(vdir->size, std::uint64_t(r.meta().voxel_count) * 8 * 16);
  EXPECT_TRUE(verify_vxl(dir.file("random.vxl")).valid) << verify_vxl(dir.file("random.vxl")).problem;
  // The stored directions are the generator's for each voxel's coordinate.
  OrderSetSpec set = parse_order_set("random:8");
  std::vector<std::array<float, 3>> expected(8);
  for (std::size_t i = 0; i < r.voxels().size(); ++i) {
    voxel_directions(set, r.voxels()[i].coord, expected);
    for (std::uint32_t k = 0; k < 8; ++k)
      ASSERT_EQ(std::memcmp(r.directions_of(i)[k].xyz, expected[k].data(), 12), 0) << "voxel " << i;
  }
  // The same input converts to the same bytes.
  convert_synth(dir, "random:8", 10.0, "random2.vxl");
  EXPECT_EQ(test::run_program("cmp", dir.file("random.vxl") + " " + dir.file("random2.vxl")).exit_code, 0);
}

TEST(OrderSets, AnEmptyTractogramConvertsWithARandomSet) {
  ScratchDir dir;
  Tractogram t;
  t.source.path = "empty";
  ConvertSettings c;
  c.orders = "random:4";
  convert_tractogram(std::move(t), dir.file("empty.vxl"), c);
  VxlFile f = VxlFile::open(dir.file("empty.vxl"));
  ASSERT_NE(f.find_section(section_id("VDIR")), nullptr);
  EXPECT_EQ(f.find_section(section_id("VDIR"))->size, 0u);
  EXPECT_TRUE(verify_vxl(dir.file("empty.vxl")).valid);
}

// Overwrites n bytes of a file at `offset`.
void patch_file(const std::string& path, std::uint64_t offset, const void* bytes, std::size_t n) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(offset));
  f.write(static_cast<const char*>(bytes), static_cast<std::streamsize>(n));
}

TEST(OrderSets, ReadersRefuseInconsistentOrUnknownPerVoxelDirections) {
  ScratchDir dir;
  std::uint64_t vdir_entry = 0, meta_offset = 0;
  {
    VxlFile r = convert_synth(dir, "random:4", 10.0, "random.vxl");
    for (std::size_t i = 0; i < r.sections().size(); ++i)
      if (std::memcmp(r.sections()[i].id, "VDIR", 4) == 0) vdir_entry = 64 + 32 * i;
    meta_offset = r.find_section(section_id("META"))->offset;
  }
  ASSERT_NE(vdir_entry, 0u);
  std::filesystem::copy_file(dir.file("random.vxl"), dir.file("unknown.vxl"));
  std::filesystem::copy_file(dir.file("random.vxl"), dir.file("no_random.vxl"));
  // What a 1.0 reader sees: a required section it does not know.
  patch_file(dir.file("unknown.vxl"), vdir_entry, "VDIX", 4);
  try {
    VxlFile::open(dir.file("unknown.vxl"));
    ADD_FAILURE() << "opened a file with an unknown required section";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
  }
  // VDIR with an order set that has shared directions.
  const std::uint32_t axis = 0;
  patch_file(dir.file("no_random.vxl"), meta_offset + 100, &axis, 4);
  EXPECT_THROW(VxlFile::open(dir.file("no_random.vxl")), Error);
}

// One voxel, orthographic views at angle `deg` from -X towards -Y in the XY plane: the axis set's
// boundary between the X and Y orders is at 45 degrees.
struct HysteresisScene {
  ScratchDir dir;
  VxlFile file = make();
  SceneLayout layout{file, 1u << 30};
  VxlFile make() {
    Tractogram t;
    const float p[] = {1, 1, 1, 2, 3, 2, 4, 2, 3};
    t.add_streamline(p, 3);
    t.source.path = "one_voxel";
    ConvertSettings c;
    c.voxel_size = 10;
    convert_tractogram(std::move(t), dir.file("one.vxl"), c);
    return VxlFile::open(dir.file("one.vxl"));
  }
  std::pair<std::uint32_t, bool> plan(FramePlan& p, double deg) {
    Camera cam;
    cam.orthographic = true;
    cam.elevation_deg = 0;
    cam.azimuth_deg = 90 - deg;  // forward (-sin az, -cos az, 0) = (-cos deg, -sin deg, 0)
    cam.frame({1, 1, 1}, {4, 3, 3}, 1.0);
    plan_frame(layout, view_of(cam), PlanOrder::Nearest, p);
    EXPECT_EQ(p.first.size(), 1u);
    return planned_order(layout, 0, p.first[0]);
  }
};

TEST(OrderSets, HysteresisKeepsTheOrderWithinTheMarginAndSwitchesBeyondIt) {
  HysteresisScene s;
  FramePlan off, on;
  on.order_hysteresis = 0.1;
  const std::uint32_t x = 0, y = 1;
  EXPECT_EQ(s.plan(off, 40).first, x);
  EXPECT_EQ(s.plan(on, 40).first, x);
  // Just past the boundary: cos 47° - sin 47° = 0.05 < 0.1, so the hysteresis keeps X.
  EXPECT_EQ(s.plan(off, 47).first, y);
  EXPECT_EQ(s.plan(on, 47).first, x);
  // Far past it: cos 55° - sin 55° = 0.245 > 0.1, so it switches, and then keeps Y on the way back.
  EXPECT_EQ(s.plan(on, 55).first, y);
  EXPECT_EQ(s.plan(on, 43).first, y);
  EXPECT_EQ(s.plan(off, 43).first, x);
  // Turning it off forgets the previous orders.
  on.order_hysteresis = 0;
  EXPECT_EQ(s.plan(on, 43).first, x);
  EXPECT_TRUE(on.previous_order.empty());
}

}  // namespace
}  // namespace vxl
