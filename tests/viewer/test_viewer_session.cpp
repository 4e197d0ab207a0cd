// The scene voxview shows (viewer_session.h): one renderer per level, made once with the image and the
// current groups, and a view's level measured on the layouts exactly as the renderers would measure it
// (the lines' bounds joined with the image's box).
#include <functional>

#include "converter/synth/synth.h"
#include "tests/nifti_test_files.h"
#include "tests/viewer/render_support.h"
#include "viewer/app/viewer_session.h"

namespace vxl::app {
namespace {

using test::gl_context;
using test::ScratchDir;

class ViewerSessionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    gl_context();
    SynthSettings synth;
    synth.streamlines = 6000;
    ConvertSettings s;
    s.voxel_size = 10;
    s.levels = 3;
    convert_tractogram(synthesize_tractogram(synth), dir.file("scene.vxl"), s);
    // An image reaching beyond the lines in +x: the projection's depth range covers it too.
    const std::array<std::int64_t, 3> dims{8, 8, 8};
    test::write_nifti_int16(dir.file("t1.nii"), dims, std::vector<std::int16_t>(8 * 8 * 8, 100),
                            {25, 0, 0, -60, 0, 25, 0, -100, 0, 0, 25, -80});
    options.inputs = {dir.file("scene.vxl")};
    file.emplace(VxlFile::open(dir.file("scene.vxl")));
    options.image = dir.file("t1.nii");
    // Small spans, so that a slab touches only some of them.
    options.span_texels = SceneLayout::largest_voxel_texels(std::vector<const VxlFile*>{&*file});
  }
  static Camera view() { return test::synth_brain_view(200); }
  // check(session) for the budgets of k/48 of full detail's bytes in the driver's largest spans (k = 1, 2, ...) whose
  // scene level is coarser than full detail, each session's detail chosen by default (paging spans) for one renderer;
  // the budgets below the coarsest level are passed over.
  void for_each_paging_budget(const std::function<void(ViewerSession&)>& check) {
    options.span_texels.reset();
    const std::vector<const VxlFile*> files{&*file};
    const std::uint64_t full = SceneLayout(files, GpuScene::driver_limit(), 0).upload_bytes();
    for (int k = 1; k < 48; ++k) {
      options.gpu_memory = full * k / 48;
      ViewerSession session(options);
      try {
        session.choose_detail(options, /*one_renderer=*/true);
      } catch (const Error&) {
        continue;
      }
      if (session.detail().level == 0) return;
      check(session);
    }
  }
  ScratchDir dir;
  ViewerOptions options;
  std::optional<VxlFile> file;
};

TEST_F(ViewerSessionTest, RenderersAreMadeOncePerLevelWithTheImage) {
  ViewerSession session(options);
  ASSERT_NE(session.image(), nullptr);
  session.choose_detail(options);
  Renderer& coarse = session.renderer_at(1, false);
  EXPECT_EQ(&session.renderer_at(1, false), &coarse);
  EXPECT_NE(&session.renderer_at(0, false), &coarse);
  EXPECT_EQ(coarse.layout().level(), 1u);
  EXPECT_TRUE(coarse.has_volume());
  EXPECT_EQ(session.bounds().min, coarse.scene_min()) << "the views are measured with the renderers' bounds";
  EXPECT_EQ(session.bounds().max, coarse.scene_max());
  EXPECT_GT(session.bounds().max.x, coarse.bounds_max().x) << "the image reaches beyond the lines";
  EXPECT_EQ(session.levels_in_files(), 3u);
}

TEST_F(ViewerSessionTest, OneRendererDrawsALevelThatFitsInTheLargestSpans) {
  options.span_texels.reset();  // the defaults: paging spans where full detail does not fit the budget
  const std::vector<const VxlFile*> files{&*file};
  options.gpu_memory = SceneLayout(files, GpuScene::driver_limit(), 0).upload_bytes() / 3;
  for (const bool one_renderer : {false, true}) {
    ViewerSession session(options);
    session.choose_detail(options, one_renderer);
    const SceneDetail& d = session.detail();
    ASSERT_GT(d.level, 0u) << "the test needs a budget that full detail does not fit";
    EXPECT_LT(d.span_texels, d.whole_span_texels) << "paging spans, smaller than the driver's";
    // The scene's level and coarser ones fit whole: one renderer takes them in the largest spans; a finer level
    // (a close view's) pages, as every level of the window's renderers, which share the budget.
    EXPECT_EQ(session.span_texels_at(d.level), one_renderer ? d.whole_span_texels : d.span_texels);
    EXPECT_EQ(session.span_texels_at(d.level + 1), one_renderer ? d.whole_span_texels : d.span_texels);
    EXPECT_EQ(session.span_texels_at(d.level - 1), d.span_texels);
    EXPECT_EQ(session.renderer_at(d.level, false).layout().level(), d.level);
  }
}

TEST_F(ViewerSessionTest, AViewsLevelIsTheOneItsRenderersWouldMeasure) {
  const std::vector<const VxlFile*> files{&*file};
  const std::uint64_t whole = SceneLayout(files, *options.span_texels, 0).upload_bytes();
  Clipping slab;
  slab.slab_mm = 6;
  bool finer_than_the_scene = false;
  for (int k = 1; k < 12; ++k) {
    const std::uint64_t budget = whole * k / 12;
    options.gpu_memory = budget;
    ViewerSession session(options);
    session.choose_detail(options);
    const SceneDetail& d = session.detail();
    std::uint32_t measured = d.level;  // as the window measured it before: with every level's renderer
    for (std::uint32_t level = 0; level < d.level; ++level)
      if (session.renderer_at(level, false).view_bytes(view(), 1.5, slab) <= d.budget) {
        measured = level;
        break;
      }
    const Camera camera = view();
    EXPECT_EQ(session.picture_levels(&camera, 1.5, slab).level, measured) << "budget " << budget;
    EXPECT_EQ(session.picture_levels(nullptr, 1.5, slab).level, d.level) << "a turntable: the whole scene's level";
    finer_than_the_scene |= measured < d.level;
  }
  EXPECT_TRUE(finer_than_the_scene) << "the test needs a budget where the slab is drawn finer than the scene";
}

// Focus first, as the window and headless rendering both ask for it: the focus at full detail and the context
// at the level that fits the rest where the picture is coarser than full detail; one level for all where the
// copy does not fit (and the focus dropped), where the picture is at full detail anyway, or under --level.
TEST_F(ViewerSessionTest, FocusFirstIsOnePolicyForEveryPicture) {
  const std::vector<const VxlFile*> files{&*file};
  const std::uint64_t whole = SceneLayout(files, *options.span_texels, 0).upload_bytes();
  std::vector<std::vector<std::uint64_t>> kept(1);  // every third streamline: spread over the whole scene
  for (std::uint64_t s = 0; s < file->meta().streamline_count; s += 3) kept[0].push_back(s);
  const Camera camera = view();
  bool focus_first_seen = false, dropped_seen = false;
  for (int k = 1; k < 12; ++k) {
    options.gpu_memory = whole * k / 12;
    ViewerSession session(options);
    session.choose_detail(options);
    const PictureLevels alone = session.picture_levels(&camera, 1.5, {});
    EXPECT_EQ(session.focus_copy_needed(alone.level), alone.level > 0);
    session.set_focus(kept);
    ASSERT_TRUE(session.has_focus());
    const PictureLevels p = session.picture_levels(&camera, 1.5, {});
    EXPECT_EQ(p.level, alone.level) << "one level for all is the same with a focus";
    if (alone.level == 0) {
      EXPECT_FALSE(p.focus_first) << "a picture at full detail has no focus first";
      EXPECT_TRUE(session.has_focus()) << "kept for the coarser pictures of a moving camera";
    } else if (p.focus_first) {
      focus_first_seen = true;
      EXPECT_GE(p.context_level(), alone.level) << "the focus takes the budget first";
      EXPECT_LE(p.focus_first->focus_bytes, session.detail().budget);
    } else {
      dropped_seen = true;
      EXPECT_FALSE(session.has_focus()) << "a copy that does not fit is dropped";
      EXPECT_EQ(p.context_level(), alone.level);
    }
  }
  EXPECT_TRUE(focus_first_seen) << "the test needs a budget where focus first fits";
  EXPECT_TRUE(dropped_seen) << "the test needs a budget where the copy does not fit";
  options.gpu_memory.reset();
  options.level = 1;
  ViewerSession forced(options);
  forced.choose_detail(options);
  EXPECT_FALSE(forced.focus_copy_needed(1)) << "--level fixes the level: no focus first";
}

// The focus-first renderer (the context's files at their level and the copy at full detail, one scene) takes the
// largest spans only where both fit the budget whole in them; else it pages as the budget's choice of levels assumed.
TEST_F(ViewerSessionTest, FocusFirstTakesTheLargestSpansOnlyWhereContextAndCopyFitWhole) {
  const std::vector<const VxlFile*> files{&*file};
  std::vector<std::vector<std::uint64_t>> kept(1);
  for (std::uint64_t s = 0; s < file->meta().streamline_count; s += 3) kept[0].push_back(s);
  const FocusCopy copy(files, kept);  // as set_focus makes it
  std::vector<const VxlFile*> all = files;
  all.insert(all.end(), copy.files().begin(), copy.files().end());
  bool whole_seen = false, paging_seen = false;
  for_each_paging_budget([&](ViewerSession& session) {
    const SceneDetail& d = session.detail();
    ASSERT_LT(d.span_texels, d.whole_span_texels);
    session.set_focus(kept);
    std::vector<std::uint32_t> levels(files.size(), d.level);
    levels.resize(all.size(), 0);
    const bool fits = SceneLayout(all, d.whole_span_texels, levels).upload_bytes() <= d.budget;
    EXPECT_EQ(session.focus_first_renderer(d.level, false).layout().max_texels(),
              fits ? d.whole_span_texels : d.span_texels)
        << "budget " << d.budget;
    whole_seen |= fits;
    paging_seen |= !fits;
  });
  EXPECT_TRUE(whole_seen) << "the test needs a budget that the context and the copy fit whole";
  EXPECT_TRUE(paging_seen) << "the test needs a budget they do not fit whole";
}

}  // namespace
}  // namespace vxl::app
