// Headless render tests on Mesa llvmpipe (EGL surfaceless, no display): each transparency mode against
// hand-made scenes whose correct picture is known.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include <glm/gtc/packing.hpp>

#include "converter/synth/synth.h"
#include "tests/viewer/render_support.h"
#include "viewer/platform/image_metrics.h"
#include "viewer/render/exact_resolve.h"

namespace vxl {
namespace {

using test::gl_context;
using test::make_scene;
using test::render_image;
using test::ScratchDir;

// Three 40 mm lines crossing at (0.5, 0.5) — the centre of pixel (32, 31) below — at z = -10, 0, +10,
// in non-neighbouring 5 mm voxels. Streamlines are listed nearest first (as seen from above), so the
// dataset order is the wrong one for blending.
Tractogram crossing_lines(double offset = 0.0) {
  Tractogram t;
  auto add = [&](std::initializer_list<double> xyz) {
    std::vector<float> p;
    for (double v : xyz) p.push_back(static_cast<float>(v + offset));
    t.add_streamline(p.data(), p.size() / 3);
  };
  add({-19.5, -19.5, 10, 20.5, 20.5, 10});  // diagonal, nearest
  add({0.5, -19.5, 0, 0.5, 20.5, 0});       // along y
  add({-19.5, 0.5, -10, 20.5, 0.5, -10});   // along x, farthest
  t.source.path = "crossing_lines";
  return t;
}

Camera top_view(double offset = 0.0) {
  Camera c;
  c.target = glm::dvec3(offset);
  c.orthographic = true;
  c.ortho_height = 64;  // 1 mm per pixel on a 64 x 64 image
  c.distance = 100;
  auto v = *parse_view("axial");
  c.azimuth_deg = v[0];
  c.elevation_deg = v[1];
  return c;
}

RenderSettings settings(RenderMode mode, float opacity = 0.5f) {
  RenderSettings s;
  s.mode = mode;
  s.opacity = opacity;
  return s;
}

const std::uint8_t* centre(const Image& img) { return img.pixel(32, 31); }

using test::lit_pixels;

class RenderModes : public ::testing::Test {
 protected:
  void SetUp() override { gl_context(); }
  ScratchDir dir;
};

TEST_F(RenderModes, OpaqueShowsTheNearestLineWithItsDirectionColour) {
  VxlFile f = make_scene(dir, crossing_lines(), 5.0);
  Renderer r(f);
  Image img = render_image(r, top_view(), settings(RenderMode::Opaque), 64, 64);
  // The diagonal (colour |(1,1,0)/sqrt 2|) is nearest at the crossing.
  EXPECT_NEAR(centre(img)[0], 180, 2);
  EXPECT_NEAR(centre(img)[1], 180, 2);
  EXPECT_EQ(centre(img)[2], 0);
  EXPECT_EQ(centre(img)[3], 255) << "an opaque picture: the line's opacity is not its alpha";
  // Away from the crossing: the x line (red) on its row, the y line (green) on its column, black elsewhere.
  EXPECT_EQ(img.pixel(20, 31)[0], 255);
  EXPECT_EQ(img.pixel(20, 31)[1], 0);
  EXPECT_EQ(img.pixel(32, 45)[1], 255);
  EXPECT_EQ(img.pixel(32, 45)[0], 0);
  EXPECT_EQ(img.pixel(5, 20)[0] + img.pixel(5, 20)[1] + img.pixel(5, 20)[2], 0);
  EXPECT_EQ(img.pixel(5, 20)[3], 255);
}

// Back-to-front "over" compositing on the CPU, in double.
glm::dvec3 composite(std::initializer_list<glm::dvec3> far_to_near, double alpha) {
  glm::dvec3 c(0.0);
  for (const glm::dvec3& f : far_to_near) c = f * alpha + c * (1 - alpha);
  return c;
}

TEST_F(RenderModes, ExactEqualsCpuCompositing) {
  gl_context();
  VxlFile f = make_scene(dir, crossing_lines(), 5.0);
  Renderer r(f);
  Image img = render_image(r, top_view(), settings(RenderMode::Exact, 0.5f), 64, 64);
  const double k = 1 / std::sqrt(2.0);
  glm::dvec3 expected = composite({{1, 0, 0}, {0, 1, 0}, {k, k, 0}}, 0.5);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(centre(img)[c], expected[c] * 255, 1.0) << "channel " << c;
  // A pixel with one line only: alpha times its colour over black.
  EXPECT_NEAR(img.pixel(20, 31)[0], 0.5 * 255, 1.0);
}

TEST_F(RenderModes, AxisAndBasicEqualExactWhereThePaperGuaranteesIt) {
  VxlFile f = make_scene(dir, crossing_lines(), 5.0);
  Renderer r(f);
  Image exact = render_image(r, top_view(), settings(RenderMode::Exact), 64, 64);
  // Not merely equal: the crossing has the three lines composited far to near, and lines are drawn.
  const double k = 1 / std::sqrt(2.0);
  const glm::dvec3 right = composite({{1, 0, 0}, {0, 1, 0}, {k, k, 0}}, 0.5);
  for (RenderMode m : {RenderMode::Axis, RenderMode::Basic}) {
    Image img = render_image(r, top_view(), settings(m), 64, 64);
    ImageDiff d = compare_images(img, exact);
    EXPECT_LE(d.max_error * 255, 1.01) << render_mode_name(m);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(centre(img)[c], right[c] * 255, 1.0) << render_mode_name(m) << " channel " << c;
    EXPECT_GT(lit_pixels(img), 100) << render_mode_name(m);
  }
}

// 300 coincident green lines at opacity 0.01: 1 - 0.99^300 of full green. An 8-bit colour buffer would
// stall near 205 (each blend rounds to 1/255 and a layer adds only 2.55 levels minus 1% of what is there).
TEST_F(RenderModes, ManyFaintLayersAccumulateBeyondEightBitRounding) {
  Tractogram t;
  const float line[] = {0.5f, -19.5f, 0, 0.5f, 20.5f, 0};
  for (int i = 0; i < 300; ++i) t.add_streamline(line, 2);
  t.source.path = "faint_layers";
  VxlFile f = make_scene(dir, std::move(t), 5.0);
  Renderer r(f);
  const double expected = 255 * (1 - std::pow(0.99, 300));  // 242.5
  for (RenderMode m : {RenderMode::Axis, RenderMode::Basic, RenderMode::Unsorted, RenderMode::Exact}) {
    Image img = render_image(r, top_view(), settings(m, 0.01f), 64, 64);
    EXPECT_NEAR(img.pixel(32, 45)[1], expected, 2.0) << render_mode_name(m);
  }
}

TEST_F(RenderModes, UnsortedDiffersFromExactOnAWrongDatasetOrder) {
  VxlFile f = make_scene(dir, crossing_lines(), 5.0);
  Renderer r(f);
  Image exact = render_image(r, top_view(), settings(RenderMode::Exact), 64, 64);
  Image unsorted = render_image(r, top_view(), settings(RenderMode::Unsorted), 64, 64);
  // Nearest first, then the others over it: the far red line ends on top.
  const double k = 1 / std::sqrt(2.0);
  glm::dvec3 wrong = composite({{k, k, 0}, {0, 1, 0}, {1, 0, 0}}, 0.5);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(centre(unsorted)[c], wrong[c] * 255, 1.0) << "channel " << c;
  int difference = 0;
  for (int c = 0; c < 3; ++c) difference += std::abs(int(centre(unsorted)[c]) - int(centre(exact)[c]));
  EXPECT_GT(difference, 60);
}

TEST_F(RenderModes, FarFromTheOriginRendersTheSameImage) {
  VxlFile near_file = make_scene(dir, crossing_lines(), 5.0, "near.vxl");
  VxlFile far_file = make_scene(dir, crossing_lines(1e5), 5.0, "far.vxl");
  Renderer near_r(near_file), far_r(far_file);
  for (RenderMode m : {RenderMode::Opaque, RenderMode::Axis}) {
    Camera perspective = top_view();
    perspective.orthographic = false;
    for (const Camera& base : {top_view(), perspective}) {
      Camera far_cam = base;
      far_cam.target += glm::dvec3(1e5);
      Image a = render_image(near_r, base, settings(m), 64, 64);
      Image b = render_image(far_r, far_cam, settings(m), 64, 64);
      EXPECT_EQ(compare_images(a, b).differing_pixels, 0u) << render_mode_name(m);
      EXPECT_GT(lit_pixels(b), 100) << "the far scene must actually be drawn";
    }
  }
}

TEST_F(RenderModes, ExactInBandsEqualsExactInOnePass) {
  VxlFile f = make_scene(dir, crossing_lines(), 5.0);
  Renderer r(f);
  Image one = render_image(r, top_view(), settings(RenderMode::Exact), 64, 64);
  ExactRenderer small(r, 60);  // 60 nodes for ~125 fragments: forces several bands
  OffscreenTarget target(64, 64);
  target.bind();
  small.draw(top_view(), settings(RenderMode::Exact), 64, 64, target.framebuffer());
  Image banded{64, 64, target.read_rgba()};
  EXPECT_GE(small.passes(), 2);
  EXPECT_EQ(compare_images(one, banded).differing_pixels, 0u);
}

// A perspective view of a synthetic scene over many voxels, for the exact mode's depth passes.
Camera perspective_view() {
  Camera c;
  c.orthographic = false;
  c.azimuth_deg = 35;
  c.elevation_deg = 20;
  c.frame({-70, -105, -50}, {70, 70, 70}, 1.0);
  return c;
}

Image exact_with_capacity(Renderer& r, const Camera& camera, std::uint64_t nodes, int size, int* passes,
                          ExactResolve resolve = ExactResolve::Gpu) {
  ExactRenderer exact(r, nodes, resolve);
  EXPECT_EQ(exact.resolve(), resolve) << "this driver's compute pass composites the lists as the CPU does";
  OffscreenTarget target(size, size);
  target.bind();
  exact.draw(camera, settings(RenderMode::Exact, 0.3f), size, size, target.framebuffer());
  *passes = exact.passes();
  return Image{size, size, target.read_rgba()};
}

// The lists composited on the GPU (a compute pass) and on the CPU (the reference) give the same picture, to the
// last bit: the same floats, compositing in the same order with every operation rounded on its own. A dense
// scene (lists far longer than the pass's batch of 16), in one run and in many runs (small node buffers), and
// lines in one plane seen from above (equal depths, ordered by their colours).
TEST_F(RenderModes, ExactOnTheGpuEqualsTheCpuReference) {
  SynthSettings synth;
  synth.streamlines = 3000;
  VxlFile dense = make_scene(dir, synthesize_tractogram(synth), 10.0);
  Renderer r(dense);
  for (std::uint64_t nodes : {std::uint64_t(1) << 22, std::uint64_t(20000)}) {
    SCOPED_TRACE(nodes);
    int gpu_passes = 0, cpu_passes = 0;
    const Image gpu = exact_with_capacity(r, perspective_view(), nodes, 128, &gpu_passes, ExactResolve::Gpu);
    const Image cpu = exact_with_capacity(r, perspective_view(), nodes, 128, &cpu_passes, ExactResolve::Cpu);
    EXPECT_EQ(gpu_passes, cpu_passes);
    EXPECT_GT(lit_pixels(gpu), 1500);
    EXPECT_EQ(compare_images(gpu, cpu).differing_pixels, 0u);
  }
  VxlFile flat = make_scene(dir, crossing_lines(), 5.0, "flat.vxl");
  Renderer lines(flat);
  int passes = 0;
  const Image gpu = exact_with_capacity(lines, top_view(), 1u << 20, 64, &passes, ExactResolve::Gpu);
  const Image cpu = exact_with_capacity(lines, top_view(), 1u << 20, 64, &passes, ExactResolve::Cpu);
  EXPECT_GT(lit_pixels(gpu), 100);
  EXPECT_EQ(compare_images(gpu, cpu).differing_pixels, 0u);
}

// A GPU stores one run's fragments in an order its scheduling decides: the picture must not depend on it. The same
// fragments stored under other node indices and linked in the reverse order composite to the same floats, where
// many tie in depth with other colours and compositing them in the order stored gives other floats.
TEST(ExactLists, ThePictureDoesNotDependOnTheOrderTheFragmentsWereStored) {
  constexpr int kWidth = 16, kHeight = 4, kPixels = kWidth * kHeight;
  std::mt19937 random(11);
  struct Fragment {
    FragmentNode node;
    int pixel;
  };
  std::vector<Fragment> fragments;
  auto half_in_unit = [&] { return std::uint32_t(random() % 0x3C01u); };  // binary16 bits of [0, 1]
  for (int p = 0; p < kPixels; ++p)
    for (int k = 0; k < 2 + p % 12; ++k) {
      const float depth = 0.5f * float(random() % 3);  // three depths: ties
      std::uint32_t depth_bits;
      std::memcpy(&depth_bits, &depth, 4);
      std::array<std::uint32_t, 4> halves{};
      for (std::uint32_t& h : halves) h = half_in_unit();  // in sequence: the same data from every compiler
      fragments.push_back({{halves[0] | halves[1] << 16, halves[2] | halves[3] << 16, depth_bits, kListEnd}, p});
    }
  struct Stored {
    std::vector<std::uint32_t> heads;
    std::vector<FragmentNode> nodes;
  };
  // Fragment f under node index slot[f]; each pixel's list linked in the order given.
  auto store = [&](const std::vector<std::uint32_t>& slot, bool reverse_links) {
    Stored s{std::vector<std::uint32_t>(kPixels, kListEnd), std::vector<FragmentNode>(fragments.size())};
    for (std::size_t n = 0; n < fragments.size(); ++n) {
      const std::size_t f = reverse_links ? fragments.size() - 1 - n : n;
      const std::uint32_t i = slot[f];
      s.nodes[i] = fragments[f].node;
      s.nodes[i][3] = s.heads[fragments[f].pixel];
      s.heads[fragments[f].pixel] = i;
    }
    return s;
  };
  auto composite = [&](const Stored& s) {
    std::vector<float> image(kPixels * 4, 0.25f);
    composite_lists_on_cpu(s.heads, s.nodes, kWidth, 0, kHeight, image);
    return image;
  };
  // The rule the picture must not follow: at equal depths, the node stored first goes under.
  auto in_storage_order = [&](const Stored& s) {
    std::vector<float> image(kPixels, 0.25f);
    for (int p = 0; p < kPixels; ++p) {
      std::vector<std::uint32_t> list;
      for (std::uint32_t i = s.heads[p]; i != kListEnd; i = s.nodes[i][3]) list.push_back(i);
      std::sort(list.begin(), list.end(), [&](std::uint32_t a, std::uint32_t b) {
        return s.nodes[a][2] != s.nodes[b][2] ? s.nodes[a][2] > s.nodes[b][2] : a < b;  // depths >= 0: bits order
      });
      for (std::uint32_t i : list) {
        const float red = glm::unpackHalf2x16(s.nodes[i][0]).x, alpha = glm::unpackHalf2x16(s.nodes[i][1]).y;
        image[p] = red * alpha + image[p] * (1.0f - alpha);
      }
    }
    return image;
  };
  std::vector<std::uint32_t> identity(fragments.size()), shuffled(fragments.size());
  for (std::uint32_t i = 0; i < identity.size(); ++i) identity[i] = shuffled[i] = i;
  std::shuffle(shuffled.begin(), shuffled.end(), random);
  const Stored first = store(identity, false), second = store(shuffled, true);
  std::size_t ties = 0;
  for (const Fragment& a : fragments)
    for (const Fragment& b : fragments)
      ties += &a < &b && a.pixel == b.pixel && a.node[2] == b.node[2] && a.node[0] != b.node[0];
  EXPECT_GT(ties, 100u) << "fragments of one pixel at one depth, in other colours";
  EXPECT_NE(in_storage_order(first), in_storage_order(second)) << "where the order stored decides, it shows";
  EXPECT_EQ(composite(first), composite(second));
}

TEST_F(RenderModes, ExactInDepthPassesEqualsExactInOnePass) {
  SynthSettings synth;
  synth.streamlines = 400;
  VxlFile f = make_scene(dir, synthesize_tractogram(synth), 12.0);
  Renderer r(f);
  int one_pass = 0, many = 0;
  const Image whole = exact_with_capacity(r, perspective_view(), 1u << 22, 96, &one_pass);
  EXPECT_EQ(one_pass, 1);
  // A small node buffer: runs of voxels, back to front, composited one over another.
  const Image runs = exact_with_capacity(r, perspective_view(), 800, 96, &many);
  EXPECT_GE(many, 4);
  const int lit = lit_pixels(whole);
  EXPECT_GT(lit, 500);
  // Equal but for a few pixels where a line ends at a voxel face: a rasterised line's fragments reach up
  // to half a pixel past its end, at depths the neighbouring voxel's run may not be behind (measured: 53
  // of 9216 pixels, RMSE 0.32). Runs composited in a wrong order would change every
  // pixel where bundles overlap.
  const std::size_t differing = compare_images(whole, runs).differing_pixels;
  const double rmse = score_image(runs, whole).rmse;
  std::printf("[ exact ] %d runs against one pass: %zu of %d pixels differ, RMSE %.2f levels\n", many, differing,
              96 * 96, rmse);
  EXPECT_LE(differing, std::size_t(lit) / 10);
  EXPECT_LT(rmse, 1.0);
}

// The GPU copy (scene_layout.h): packed positions (4 bytes a vertex) and the three stored orders as the file
// packs them (16 bits an entry or fewer here: at most 6 bytes a segment) serve all six directions and the block
// order in at most 12 bytes a source point; float positions and 32-bit orders would take about 29.
TEST_F(RenderModes, TheGpuCopyTakesAtMostTwelveBytesAPoint) {
  SynthSettings synth;
  synth.streamlines = 20000;
  VxlFile f = make_scene(dir, synthesize_tractogram(synth), 10.0);
  for (const VoxelEntry& v : f.voxels()) ASSERT_LE(v.vertex_count, 65536u) << "16-bit orders throughout";
  Renderer r(f);
  const double per_point = double(r.gpu_bytes()) / double(f.meta().point_count);
  EXPECT_LE(per_point, 12.0);
  EXPECT_GT(per_point, 9.0) << "positions and orders are all there";
}

// A voxel of more than 65 536 vertices has order entries of more than 16 bits, which the vertex shader reads
// from the file's bytes across two 32-bit words where they straddle one: its stored orders must draw the same
// segments as its block order. In one fixed colour the picture does not depend on the order (every blend
// applies the same function), so the two are equal pixel for pixel; a wrong shift joins unrelated vertices.
TEST_F(RenderModes, WideVoxelsDrawTheirStoredOrdersRight) {
  SynthSettings synth;
  synth.streamlines = 1500;
  VxlFile f = make_scene(dir, synthesize_tractogram(synth), 1000.0);
  ASSERT_EQ(f.meta().voxel_count, 1u);
  ASSERT_GT(f.voxels()[0].vertex_count, 65536u);
  Renderer r(f);
  ASSERT_GT(r.layout().voxels()[0].order_bits, 16u);
  Camera cam = perspective_view();
  RenderSettings axis_settings = settings(RenderMode::Axis, 0.1f), block_settings = settings(RenderMode::Basic, 0.1f);
  axis_settings.color = block_settings.color = ColorMode::Fixed;
  const Image axis = render_image(r, cam, axis_settings, 96, 96);
  const Image block = render_image(r, cam, block_settings, 96, 96);
  EXPECT_GT(lit_pixels(axis), 1000);
  EXPECT_EQ(compare_images(axis, block).differing_pixels, 0u);
}

TEST_F(RenderModes, ExactOverSeveralGridsFallsBackToRowBands) {
  // Files on different grids overlap in space: no voxel order is a visibility order, so the runs are
  // bands of rows over all voxels.
  SynthSettings synth;
  synth.streamlines = 200;
  VxlFile a = make_scene(dir, synthesize_tractogram(synth), 12.0, "a.vxl");
  synth.seed = 2;
  VxlFile b = make_scene(dir, synthesize_tractogram(synth), 7.0, "b.vxl");
  Renderer r(std::vector<const VxlFile*>{&a, &b});
  int one_pass = 0, bands = 0;
  const Image whole = exact_with_capacity(r, perspective_view(), 1u << 22, 96, &one_pass);
  const Image banded = exact_with_capacity(r, perspective_view(), 800, 96, &bands);
  EXPECT_EQ(one_pass, 1);
  EXPECT_GE(bands, 4);
  EXPECT_GT(lit_pixels(whole), 500);
  EXPECT_EQ(compare_images(whole, banded).differing_pixels, 0u);
}

TEST_F(RenderModes, ManyTextureSpansRenderLikeOne) {
  // A tractogram spread over several voxels, uploaded with a tiny texture-buffer limit.
  Tractogram t;
  for (int s = 0; s < 40; ++s) {
    std::vector<float> p;
    for (int i = 0; i < 30; ++i)
      p.insert(p.end(), {float(-25 + 1.7 * i), float(-20 + s), float(std::sin(0.3 * i + s) * 8)});
    t.add_streamline(p.data(), 30);
  }
  VxlFile f = make_scene(dir, std::move(t), 6.0);
  // More spans than one draw binds (Renderer::kMaxBoundSpans): the draws bind them a few at a time. At a few
  // times the largest voxel's size a span holds a few voxels.
  const std::uint64_t voxel_texels = SceneLayout::largest_voxel_texels(std::vector<const VxlFile*>{&f});
  Renderer one(f), many(f, 16 * voxel_texels), more_than_a_draw_binds(f, 4 * voxel_texels);
  EXPECT_EQ(one.layout().texture_spans().size(), 1u);
  EXPECT_GT(many.layout().texture_spans().size(), 3u);
  EXPECT_GT(more_than_a_draw_binds.layout().texture_spans().size(), 2 * Renderer::kMaxBoundSpans);
  Camera cam = top_view();
  cam.azimuth_deg = 30;
  cam.elevation_deg = 40;
  for (RenderMode m : {RenderMode::Axis, RenderMode::Basic, RenderMode::Unsorted, RenderMode::Opaque, RenderMode::Wboit,
                       RenderMode::Additive, RenderMode::Exact, RenderMode::Segsort}) {
    Image a = render_image(one, cam, settings(m, 0.3f), 64, 64);
    Image b = render_image(many, cam, settings(m, 0.3f), 64, 64);
    Image c = render_image(more_than_a_draw_binds, cam, settings(m, 0.3f), 64, 64);
    EXPECT_EQ(compare_images(a, b).differing_pixels, 0u) << render_mode_name(m);
    EXPECT_EQ(compare_images(a, c).differing_pixels, 0u) << render_mode_name(m);
    EXPECT_GT(lit_pixels(a), 200) << render_mode_name(m);
  }
}

// Pixels where some channel differs by more than `levels`.
int pixels_differing(const Image& a, const Image& b, int levels) {
  int n = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x)
      for (int c = 0; c < 3; ++c)
        if (std::abs(int(a.pixel(x, y)[c]) - int(b.pixel(x, y)[c])) > levels) {
          ++n;
          break;
        }
  return n;
}

// The paper's guarantee, inside one voxel: three lines in planes z = const, all in one voxel, seen along z.
// Their dataset order is nearest first (basic is wrong), the stored z order is right (axis), and sorting each
// segment by its depth is right too (segsort).
TEST_F(RenderModes, SegsortEqualsExactInsideOneVoxelWhereThePaperGuaranteesIt) {
  VxlFile f = make_scene(dir, crossing_lines(), 100.0);
  ASSERT_EQ(f.meta().voxel_count, 1u);
  Renderer r(f);
  const Image exact = render_image(r, top_view(), settings(RenderMode::Exact), 64, 64);
  const double k = 1 / std::sqrt(2.0);
  const glm::dvec3 right = composite({{1, 0, 0}, {0, 1, 0}, {k, k, 0}}, 0.5);
  for (RenderMode m : {RenderMode::Segsort, RenderMode::Axis}) {
    const Image img = render_image(r, top_view(), settings(m), 64, 64);
    EXPECT_LE(compare_images(img, exact).max_error * 255, 1.01) << render_mode_name(m);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(centre(img)[c], right[c] * 255, 1.0) << render_mode_name(m) << " channel " << c;
    EXPECT_GT(lit_pixels(img), 100) << render_mode_name(m);
    EXPECT_EQ(r.stats().segments_drawn, 3u) << render_mode_name(m);
  }
  const Image basic = render_image(r, top_view(), settings(RenderMode::Basic), 64, 64);
  EXPECT_GT(pixels_differing(basic, exact, 30), 0) << "the scene tells a wrong order inside the voxel";
}

// Twelve straight lines in one voxel, each in its own plane perpendicular to the view direction (2.5 mm
// apart in depth), at different angles and offsets so that they cross one another many times. Seen
// orthographically along that direction, every fragment of a line has the line's depth, which is also its
// midpoint's: sorting the segments by their depth is sorting the fragments, so segsort equals exact by
// construction, from any direction. `axis` draws a stored order sorted along x, y or z: right for a view
// along that axis, wrong for some crossings in an oblique view (the lines' offsets in their planes scramble
// their order along the axis).
Tractogram fronto_parallel_lines(const Camera& c) {
  Tractogram t;
  const glm::dvec3 f = c.forward(), r = c.right(), u = c.up();
  for (int k = 0; k < 12; ++k) {
    const double depth = 2.5 * (k - 5.5), angle = 0.27 * k + 0.1;
    const double a = 7.0 * std::sin(2.3 * k + 1), b = 7.0 * std::cos(1.7 * k + 2);  // offset in the plane
    const glm::dvec3 mid = depth * f + a * r + b * u, along = 22.0 * (std::cos(angle) * r + std::sin(angle) * u);
    const glm::dvec3 p = mid - along, q = mid + along;
    const float xyz[] = {float(p.x), float(p.y), float(p.z), float(q.x), float(q.y), float(q.z)};
    t.add_streamline(xyz, 2);
  }
  t.source.path = "fronto_parallel_lines";
  return t;
}

TEST_F(RenderModes, SegsortIsNoWorseThanAxisAndExactWhereSortingSegmentsIsExact) {
  struct View {
    double azimuth, elevation;
    bool oblique;
  };
  double axis_sum = 0, segsort_sum = 0;
  int n = 0;
  for (const View v : {View{0, 0, false}, View{30, 25, true}, View{135, 40, true}, View{250, -30, true}}) {
    SCOPED_TRACE(testing::Message() << "azimuth " << v.azimuth << " elevation " << v.elevation);
    Camera cam;
    cam.orthographic = true;
    cam.ortho_height = 72;
    cam.distance = 100;
    cam.azimuth_deg = v.azimuth;
    cam.elevation_deg = v.elevation;
    VxlFile f = make_scene(dir, fronto_parallel_lines(cam), 1000.0, "lines" + std::to_string(n++) + ".vxl");
    ASSERT_EQ(f.meta().voxel_count, 1u);
    Renderer r(f);
    const Image exact = render_image(r, cam, settings(RenderMode::Exact), 96, 96);
    const Image axis = render_image(r, cam, settings(RenderMode::Axis), 96, 96);
    const Image segsort = render_image(r, cam, settings(RenderMode::Segsort), 96, 96);
    ASSERT_GT(lit_pixels(exact), 400);
    const double axis_rmse = score_image(axis, exact).rmse, segsort_rmse = score_image(segsort, exact).rmse;
    axis_sum += axis_rmse, segsort_sum += segsort_rmse;
    EXPECT_EQ(pixels_differing(segsort, exact, 1), 0) << "segsort RMSE " << segsort_rmse;
    EXPECT_LE(segsort_rmse, axis_rmse + 0.01);
    if (v.oblique) {
      EXPECT_GT(pixels_differing(axis, exact, 10), 0) << "axis RMSE " << axis_rmse;
      EXPECT_GT(axis_rmse, segsort_rmse + 0.1);
    }
  }
  EXPECT_LT(segsort_sum, axis_sum);
}

// The same segments as basic, at every level of detail, over several spans and several files: in one fixed
// colour the picture does not depend on the order inside a pixel's stack (every blend applies the same
// function), so segsort and basic draw the same picture pixel for pixel; a missing, repeated or wrong
// segment (one past its level's prefix, or joining two voxlines) changes it.
TEST_F(RenderModes, SegsortDrawsTheSegmentsOfItsLevelInEverySpanAndFile) {
  SynthSettings synth;
  synth.streamlines = 1500;
  ConvertSettings cs;
  cs.voxel_size = 12;
  cs.levels = 2;
  convert_tractogram(synthesize_tractogram(synth), dir.file("a.vxl"), cs);
  synth.seed = 2;
  synth.streamlines = 300;
  convert_tractogram(synthesize_tractogram(synth), dir.file("b.vxl"), cs);
  const VxlFile a = VxlFile::open(dir.file("a.vxl")), b = VxlFile::open(dir.file("b.vxl"));
  RenderSettings segsort = settings(RenderMode::Segsort, 0.2f), basic = settings(RenderMode::Basic, 0.2f);
  segsort.color = basic.color = ColorMode::Fixed;
  for (std::uint32_t level : {0u, 1u}) {
    SCOPED_TRACE(level);
    const std::vector<const VxlFile*> files = {&a, &b};
    Renderer r(files, SceneLayout::largest_voxel_texels(files), level);  // spans of few voxels
    ASSERT_GE(r.layout().texture_spans().size(), level == 0 ? 3u : 2u);
    const Image sorted = render_image(r, perspective_view(), segsort, 96, 96);
    const std::uint64_t segments = r.stats().segments_drawn;
    const Image block = render_image(r, perspective_view(), basic, 96, 96);
    EXPECT_EQ(segments, r.stats().segments_drawn);
    EXPECT_GT(lit_pixels(sorted), 800);
    // Equal but for rounding: llvmpipe's blends differ by a level in a few pixels between draw orders even
    // in one colour (axis against basic the same); a segment missing or added changes a pixel by far more.
    EXPECT_LE(compare_images(sorted, block).max_error * 255, 1.01);
    EXPECT_EQ(lit_pixels(sorted), lit_pixels(block));
  }
}

// The dataset buffers hold either the streamline order or the view order: switching between unsorted and
// segsort rebuilds what the other replaced.
TEST_F(RenderModes, UnsortedAndSegsortTakeTurnsWithTheDatasetBuffers) {
  SynthSettings synth;
  synth.streamlines = 300;
  VxlFile f = make_scene(dir, synthesize_tractogram(synth), 12.0);
  Renderer r(f);
  const Image unsorted = render_image(r, perspective_view(), settings(RenderMode::Unsorted), 96, 96);
  const std::uint64_t bytes = r.gpu_bytes();
  const Image segsort = render_image(r, perspective_view(), settings(RenderMode::Segsort), 96, 96);
  EXPECT_GT(compare_images(unsorted, segsort).differing_pixels, 0u);
  EXPECT_EQ(compare_images(unsorted, render_image(r, perspective_view(), settings(RenderMode::Unsorted), 96, 96))
                .differing_pixels,
            0u);
  EXPECT_EQ(r.gpu_bytes(), bytes) << "one of the two orders on the GPU at a time";
  EXPECT_EQ(compare_images(segsort, render_image(r, perspective_view(), settings(RenderMode::Segsort), 96, 96))
                .differing_pixels,
            0u);
}

TEST_F(RenderModes, OrderIndependentModesDrawSomethingBetweenBackgroundAndOpaque) {
  VxlFile f = make_scene(dir, crossing_lines(), 5.0);
  Renderer r(f);
  for (RenderMode m : {RenderMode::Wboit, RenderMode::Additive}) {
    Image img = render_image(r, top_view(), settings(m, 0.5f), 64, 64);
    int red = img.pixel(20, 31)[0];
    EXPECT_GT(red, 20) << render_mode_name(m);
    EXPECT_LT(red, 255) << render_mode_name(m);
    EXPECT_EQ(img.pixel(5, 20)[0], 0) << render_mode_name(m);
  }
}

}  // namespace
}  // namespace vxl
