// The renderer's parts below Renderer: the table of the modes' passes (modes/mode_table.cpp) and the line
// pass (line_pass.h), whose draws bind a frame plan's spans a few at a time.
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

#include "converter/synth/synth.h"
#include "tests/viewer/render_support.h"
#include "viewer/platform/image_metrics.h"
#include "viewer/render/clip_uniforms.h"
#include "viewer/render/line_pass.h"
#include "viewer/render/modes/blend_states.h"
#include "viewer/render/modes/mode_pass.h"
#include "viewer/render/scene_groups.h"
#include "viewer/render/view_queries.h"

namespace vxl {
namespace {

using test::gl_context;
using test::ScratchDir;

TEST(ModeTable, EveryModeIsDrawnByItsOwnPass) {
  for (const RenderModeInfo& info : render_modes()) {
    const std::unique_ptr<ModePass> pass = make_mode_pass(info.mode);
    ASSERT_NE(pass, nullptr) << info.name;
    EXPECT_EQ(pass->mode(), info.mode) << info.name;
  }
}

TEST(ModeTable, OnlyTheSortedModesDrawInPiecesOfVoxels) {
  // Renderer::begin_pieces: opaque, basic and axis in runs of plan voxels, in their own plan order; exact in
  // its own runs; the modes that blend in no order (or sort on the CPU) in one piece.
  for (const RenderModeInfo& info : render_modes()) {
    const std::unique_ptr<ModePass> pass = make_mode_pass(info.mode);
    const PieceKind expected =
        info.mode == RenderMode::Opaque || info.mode == RenderMode::Basic || info.mode == RenderMode::Axis
            ? PieceKind::Voxels
        : info.mode == RenderMode::Exact ? PieceKind::Own
                                         : PieceKind::Whole;
    EXPECT_EQ(pass->piece_kind(), expected) << info.name;
  }
  RenderSettings s;
  s.order_hysteresis = 0.25f;
  FramePlan plan;
  EXPECT_EQ(make_mode_pass(RenderMode::Opaque)->plan_order(s, plan), PlanOrder::Any);
  EXPECT_EQ(make_mode_pass(RenderMode::Basic)->plan_order(s, plan), PlanOrder::Block);
  EXPECT_EQ(plan.order_hysteresis, 0.0f) << "only the nearest-order pick keeps orders across frames";
  EXPECT_EQ(make_mode_pass(RenderMode::Axis)->plan_order(s, plan), PlanOrder::Nearest);
  EXPECT_EQ(plan.order_hysteresis, 0.25f);
  EXPECT_THROW(make_mode_pass(RenderMode::Wboit)->plan_order(s, plan), std::logic_error);
}

class LinePassSpans : public ::testing::Test {
 protected:
  void SetUp() override { gl_context(); }
  ScratchDir dir;
};

// The scene's lines drawn back to front with the over program, straight through a LinePass (no Renderer).
// With `own_draw`, the draws are planned (LinePass::plan_draws) with that many segments per run from which a draw
// binds one span, and `slots` is what a draw then binds.
Image draw_through_line_pass(const VxlFile& f, std::uint64_t max_texels, std::size_t* spans, unsigned* slots,
                             std::optional<std::uint64_t> own_draw = std::nullopt) {
  const std::vector<const VxlFile*> files = {&f};
  GpuScene scene(files, max_texels);
  LinePass lines(scene, files);
  *spans = scene.layout().texture_spans().size();
  *slots = lines.bound_spans();
  Camera camera;
  camera.orthographic = false;
  camera.azimuth_deg = 35;
  camera.elevation_deg = 20;
  camera.frame({-70, -105, -50}, {70, 70, 70}, 1.0);
  const SceneBounds bounds = line_bounds(files);
  const glm::dmat4 projection = fitted_projection(camera, 1.0, bounds, scene.layout().voxel_size());
  FramePlan plan;
  plan_view(scene.layout(), camera, projection, PlanOrder::Nearest, plan, {});
  EXPECT_TRUE(scene.make_resident(spans_nearest_first(scene.layout(), plan)).complete);
  if (own_draw) {
    lines.plan_draws(plan.first, plan.count, *own_draw);
    *slots = lines.draw_spans();
  }
  RenderSettings settings;
  settings.opacity = 0.3f;
  const SceneGroups groups(files);
  OffscreenTarget target(96, 96);
  target.bind();
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  over_blending();
  lines.bind(lines.over(), LineUniforms{camera, projection, settings, {0.0f, 1.0f}, groups, 0});
  lines.draw_plan(lines.over(), plan.first, plan.count);
  glFinish();
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  enable_clip_distances(0);
  return Image{96, 96, target.read_rgba()};
}

TEST_F(LinePassSpans, APlanOverMoreSpansThanSlotsDrawsAsOverOneSpan) {
  SynthSettings synth;
  synth.streamlines = 400;
  const VxlFile f = test::make_scene(dir, synthesize_tractogram(synth), 12.0);
  const std::vector<const VxlFile*> files = {&f};
  std::size_t one_span = 0, many_spans = 0;
  unsigned one_slot = 0, slots = 0;
  const Image whole = draw_through_line_pass(f, 0, &one_span, &one_slot);
  ASSERT_EQ(one_span, 1u);
  // Spans of about the largest voxel each: more than the program's slots, so draw_plan rebinds them as
  // the plan goes, each run in the plan's order.
  const std::uint64_t texels = SceneLayout::largest_voxel_texels(files);
  const Image split = draw_through_line_pass(f, texels, &many_spans, &slots);
  ASSERT_GT(many_spans, std::size_t(slots)) << "the scene must need more spans than one draw binds";
  EXPECT_GT(test::lit_pixels(whole), 500);
  EXPECT_EQ(compare_images(whole, split).differing_pixels, 0u);
}

// Where a plan's runs of voxels in one span are long, a draw binds one span with the programs made for one slot:
// the same picture as the draws over several spans, and as the scene in one span.
TEST_F(LinePassSpans, LongRunsAreDrawnOneSpanADrawWithTheSamePicture) {
  SynthSettings synth;
  synth.streamlines = 400;
  const VxlFile f = test::make_scene(dir, synthesize_tractogram(synth), 12.0);
  const std::vector<const VxlFile*> files = {&f};
  const std::uint64_t texels = SceneLayout::largest_voxel_texels(files);
  std::size_t spans = 0, one_span = 0;
  unsigned slots = 0, whole_slots = 0;
  const Image whole = draw_through_line_pass(f, 0, &one_span, &whole_slots);
  const Image several = draw_through_line_pass(f, texels, &spans, &slots, std::numeric_limits<std::uint64_t>::max());
  ASSERT_GT(spans, 1u);
  ASSERT_GT(slots, 1u) << "runs never long enough: draws bind several spans";
  const Image one_a_draw = draw_through_line_pass(f, texels, &spans, &slots, 0);
  EXPECT_EQ(slots, 1u) << "every run long enough: a draw binds one span";
  EXPECT_GT(test::lit_pixels(whole), 500);
  EXPECT_EQ(compare_images(several, one_a_draw).differing_pixels, 0u);
  EXPECT_EQ(compare_images(whole, one_a_draw).differing_pixels, 0u);
  // The default threshold: this scene's runs are far shorter than kSegmentsPerOwnDraw.
  draw_through_line_pass(f, texels, &spans, &slots, LinePass::kSegmentsPerOwnDraw);
  EXPECT_GT(slots, 1u);
}

TEST_F(LinePassSpans, AnEmptyPlanDrawsNothing) {
  Tractogram t;
  const float line[] = {-10, 0, 0, 10, 0, 0};
  t.add_streamline(line, 2);
  t.source.path = "one_line";
  const VxlFile f = test::make_scene(dir, std::move(t), 5.0);
  const std::vector<const VxlFile*> files = {&f};
  GpuScene scene(files);
  LinePass lines(scene, files);
  OffscreenTarget target(16, 16);
  target.bind();
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  lines.draw_plan(lines.over(), {}, {});
  EXPECT_EQ(test::lit_pixels(Image{16, 16, target.read_rgba()}), 0);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

}  // namespace
}  // namespace vxl
