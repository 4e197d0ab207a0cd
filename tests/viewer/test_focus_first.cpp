// Focus first under a budget (view_level.h, focus_copy.h): when the GPU memory budget forces the scene
// coarser than full detail, a selection's focus is drawn from a full-detail copy of its own, whose bytes
// count first, and the context at the finest level that fits what is left — in one scene, one pass.
// The level choice is checked on layouts alone (no GL); the pictures through voxview.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "converter/convert/convert.h"
#include "converter/synth/synth.h"
#include "format/vxl_file.h"
#include "tests/viewer/render_support.h"
#include "viewer/app/focus_copy.h"
#include "viewer/app/view_level.h"
#include "viewer/render/scene_groups.h"

namespace vxl::app {
namespace {

using test::ScratchDir;

class FocusFirst : public ::testing::Test {
 protected:
  void SetUp() override {
    SynthSettings synth;
    synth.streamlines = 6000;
    tractogram = synthesize_tractogram(synth);
    ConvertSettings s;
    s.voxel_size = 10;
    s.levels = 3;
    convert_tractogram(Tractogram(tractogram), dir.file("scene.vxl"), s);
    file.emplace(VxlFile::open(dir.file("scene.vxl")));
  }
  std::vector<const VxlFile*> files() const { return {&*file}; }
  std::uint64_t span_texels() const {
    return std::max<std::uint64_t>(4096, SceneLayout::largest_voxel_texels(files()));
  }
  // Every 60th streamline: a focus spread over the whole scene, as a selection of a large bundle is.
  std::vector<std::vector<std::uint64_t>> every_60th() const {
    std::vector<std::vector<std::uint64_t>> kept(1);
    for (std::uint64_t s = 0; s < file->meta().streamline_count; s += 60) kept[0].push_back(s);
    return kept;
  }
  static Camera view() { return test::synth_brain_view(); }
  ScratchDir dir;
  Tractogram tractogram;
  std::optional<VxlFile> file;
};

TEST_F(FocusFirst, TheFocusTakesFullDetailFirstAndTheContextTheLevelThatFitsTheRest) {
  const std::vector<std::vector<std::uint64_t>> kept = every_60th();
  const FocusCopy copy(files(), kept);
  ASSERT_EQ(copy.files().size(), 1u);
  EXPECT_EQ(copy.files()[0]->meta().streamline_count, kept[0].size());
  LevelLayouts context(files(), span_texels());
  const SceneLayout focus(copy.files(), span_texels(), 0);
  const SceneBounds bounds = scene_bounds(files(), nullptr);
  const LayoutBytes bytes = visible_bytes(view(), 1.0, bounds, {});
  const std::uint64_t at0 = bytes(context.at(0)), at1 = bytes(context.at(1)), at2 = bytes(context.at(2));
  const std::uint64_t focus_bytes = bytes(focus);
  ASSERT_GT(focus_bytes, 0u);
  ASSERT_LT(at1 + focus_bytes, at0) << "the scene's sizes this test needs";
  ASSERT_LT(at2 + focus_bytes, at1);

  SceneDetail detail;
  detail.level = 1;  // the whole scene fits at level 1
  // Too small for the whole scene at full detail: one level for all would be level 1; focus first, the
  // focus at level 0 and the context at level 1.
  detail.budget = at0 - 1;
  EXPECT_EQ(level_for_view(context, detail, view(), 1.0, bounds, {}), 1u);
  std::optional<FocusFirstLevels> levels = focus_first_levels(context, focus, detail, bytes);
  ASSERT_TRUE(levels);
  EXPECT_EQ(levels->context, 1u);
  EXPECT_EQ(levels->focus_bytes, focus_bytes);
  // The focus counts first: a budget that holds level 1 alone, but not beside the focus, takes the context
  // one level coarser, coarser than the scene's level.
  detail.budget = at1;
  EXPECT_EQ(level_for_view(context, detail, view(), 1.0, bounds, {}), 1u);
  levels = focus_first_levels(context, focus, detail, bytes);
  ASSERT_TRUE(levels);
  EXPECT_EQ(levels->context, 2u);
  // No room for the focus beside even the coarsest context, or --level: one level for all, as before.
  detail.budget = at2 + focus_bytes - 1;
  EXPECT_FALSE(focus_first_levels(context, focus, detail, bytes));
  detail.budget = at0 - 1;
  detail.forced = true;
  EXPECT_FALSE(focus_first_levels(context, focus, detail, bytes));

  // The scene drawn: the context's file at its level and the copy at full detail in one layout, whose
  // bytes are the two parts' (what the choice measured).
  std::vector<const VxlFile*> both = files();
  both.push_back(copy.files()[0]);
  const std::vector<std::uint32_t> file_levels = {1, 0};
  const SceneLayout scene(both, span_texels(), file_levels);
  EXPECT_EQ(scene.level(), 1u);
  EXPECT_FALSE(scene.one_level());
  EXPECT_EQ(scene.files()[0].level, 1u);
  EXPECT_EQ(scene.files()[1].level, 0u);
  EXPECT_EQ(bytes(scene), at1 + focus_bytes);
}

TEST_F(FocusFirst, WithoutASelectionThereIsNoCopyAndTheLevelIsUnchanged) {
  const FocusCopy none(files(), {{}});
  EXPECT_TRUE(none.files().empty());
  // One level for every file is the same layout as that level alone.
  LevelLayouts context(files(), span_texels());
  const std::vector<std::uint32_t> one = {1};
  const SceneLayout same(files(), span_texels(), one);
  EXPECT_TRUE(same.one_level());
  EXPECT_EQ(same.upload_bytes(), context.at(1).upload_bytes());
  EXPECT_EQ(same.voxels().size(), context.at(1).voxels().size());
}

TEST_F(FocusFirst, TheSelectedStreamlinesInTheContextsFilesAreHidden) {
  const std::vector<std::vector<std::uint64_t>> kept = every_60th();
  const FocusCopy copy(files(), kept);
  std::vector<const VxlFile*> both = files();
  both.push_back(copy.files()[0]);
  const SceneGroups groups = SceneGroups::focus_first(both, 1, kept);
  ASSERT_EQ(groups.groups().size(), 3u);
  EXPECT_EQ(groups.groups()[0].name, SceneGroups::kSelected);
  EXPECT_EQ(groups.groups()[1].name, SceneGroups::kContext);
  EXPECT_FALSE(groups.groups()[0].hidden);
  EXPECT_TRUE(groups.groups()[2].hidden);
  EXPECT_EQ(groups.groups()[0].streamlines, kept[0].size());
  EXPECT_EQ(groups.groups()[1].streamlines, file->meta().streamline_count - kept[0].size());
  EXPECT_EQ(groups.group_of(0, 60), 2u) << "selected, drawn from the copy";
  EXPECT_EQ(groups.group_of(0, 61), 1u);
  EXPECT_TRUE(groups.uniform(1));
  EXPECT_EQ(groups.group_of(1, 0), 0u);
  // The table the renderer uploads says the same of every streamline, taken modulo the shader's groups.
  const std::uint64_t n = file->meta().streamline_count;
  std::vector<std::uint8_t> table(n, 255), two(n, 255);
  groups.write_table(0, table, 256);
  groups.write_table(0, two, 2);
  for (std::uint64_t s = 0; s < n; ++s) {
    ASSERT_EQ(table[s], groups.group_of(0, s)) << s;
    ASSERT_EQ(two[s], groups.group_of(0, s) % 2) << s;
  }
  std::vector<std::uint8_t> copy_table(copy.files()[0]->meta().streamline_count, 255);
  groups.write_table(1, copy_table, 256);
  EXPECT_TRUE(std::all_of(copy_table.begin(), copy_table.end(), [](std::uint8_t g) { return g == 0; }));
}

// Pixels of the focus colour (pure red) in a picture.
int red_pixels(const Image& img) {
  int n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = img.pixel(x, y);
      n += p[0] > 200 && p[1] < 40 && p[2] < 40;
    }
  return n;
}

double red_sum(const Image& img) {
  double sum = 0;
  for (std::size_t i = 0; i < img.rgba.size(); i += 4) sum += img.rgba[i];
  return sum;
}

// voxview under a budget that forces the scene coarser draws the focus as it draws it without a budget
// (every selected streamline), and says at which levels it drew focus and context; --level 1 (one level for
// all) loses most of the focus.
TEST_F(FocusFirst, VoxviewDrawsTheFocusAtFullDetailUnderABudgetThatTakesTheContextCoarser) {
  test::gl_context();
  // A sphere around the middle of streamline 0: a bundle's worth of streamlines.
  const std::uint64_t middle = (tractogram.offsets[0] + tractogram.offsets[1]) / 2;
  const float* p = &tractogram.positions[3 * middle];
  const std::string sphere = std::to_string(p[0]) + "," + std::to_string(p[1]) + "," + std::to_string(p[2]) + ",8";
  const std::uint64_t level_1 = SceneLayout(files(), span_texels(), 1).upload_bytes();
  auto voxview = [&](const std::string& png, const std::string& args) {
    const test::CommandResult r =
        test::run_program(VOXVIEW_CLI, test::q(dir.file("scene.vxl")) + " --render " + test::q(dir.file(png)) +
                                           " --size 128x128 --view axial --span-texels 4096 --include=" + sphere +
                                           " --color group --group selected=#ff0000 " + args);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return r.output;
  };
  const std::string budget = " --gpu-memory " + std::to_string(level_1);
  const std::string alone = " --focus-opacity 1 --context-opacity 0";
  voxview("full.png", alone);
  const std::string said = voxview("budget.png", alone + budget);
  EXPECT_NE(said.find("focus first: the "), std::string::npos) << said;
  EXPECT_NE(said.find("focus at level 0 and context at level "), std::string::npos) << said;
  EXPECT_EQ(said.find("context at level 0"), std::string::npos) << said;
  voxview("level1.png", alone + " --level 1");
  const Image full = read_image(dir.file("full.png")), budgeted = read_image(dir.file("budget.png")),
              coarse = read_image(dir.file("level1.png"));
  const int focus_full = red_pixels(full);
  ASSERT_GT(focus_full, 200);
  // Every selected streamline drawn: the focus's pixels as without a budget (a pixel or two may differ: the
  // copy's voxels are cut on their own grid, so segments meet the pixels in another order).
  int missing = 0;
  for (int y = 0; y < full.height; ++y)
    for (int x = 0; x < full.width; ++x) missing += full.pixel(x, y)[0] > 200 && budgeted.pixel(x, y)[0] <= 200;
  EXPECT_LE(missing, focus_full / 100) << "focus pixels lost under the budget, of " << focus_full;
  EXPECT_LT(red_pixels(coarse), focus_full * 3 / 4) << "one level for all draws fewer focus streamlines";
  // The selected streamlines' coarse copies in the context's file are not drawn (nor in another colour).
  int other = 0;
  for (int y = 0; y < budgeted.height; ++y)
    for (int x = 0; x < budgeted.width; ++x) other += budgeted.pixel(x, y)[1] > 60 || budgeted.pixel(x, y)[2] > 60;
  EXPECT_EQ(other, 0);
  // With the context shown, it is drawn (at the coarser level) around the full focus.
  const std::string shown = voxview("context.png", "--focus-opacity 1 --context-opacity 0.2" + budget);
  EXPECT_NE(shown.find("focus at level 0 and context at level "), std::string::npos) << shown;
  const Image with_context = read_image(dir.file("context.png"));
  EXPECT_GT(test::lit_pixels(with_context), test::lit_pixels(budgeted));
  EXPECT_GE(red_pixels(with_context), focus_full / 2);
  // A translucent focus keeps its brightness: its opacity is not compensated for the context's level.
  voxview("faint_full.png", " --focus-opacity 0.3 --context-opacity 0");
  voxview("faint_budget.png", " --focus-opacity 0.3 --context-opacity 0" + budget);
  const double faint_full = red_sum(read_image(dir.file("faint_full.png")));
  EXPECT_GT(faint_full, 0);
  EXPECT_NEAR(red_sum(read_image(dir.file("faint_budget.png"))) / faint_full, 1.0, 0.02);
}

}  // namespace
}  // namespace vxl::app
