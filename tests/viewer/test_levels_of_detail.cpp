// Drawing a coarse level of detail (.vxl spec §5.12, §6.5): it uploads and draws only its own part of each
// voxel, its opacity compensated so that the picture keeps its brightness, and the level chosen for a GPU
// memory budget never exceeds it.
#include <cmath>
#include <filesystem>
#include <numeric>

#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "tests/viewer/render_support.h"
#include "viewer/platform/image_metrics.h"
#include "viewer/render/scene_layout.h"

namespace vxl {
namespace {

using test::gl_context;
using test::render_image;
using test::ScratchDir;

class LevelsOfDetail : public ::testing::Test {
 protected:
  void SetUp() override {
    gl_context();
    SynthSettings synth;
    synth.streamlines = 12000;
    ConvertSettings s;
    s.voxel_size = 10;
    s.levels = 4;
    convert_tractogram(synthesize_tractogram(synth), dir.file("scene.vxl"), s);
  }
  VxlFile file() const { return VxlFile::open(dir.file("scene.vxl")); }
  ScratchDir dir;
};

std::uint64_t level_segments(const VxlFile& f, std::uint32_t level) {
  std::uint64_t n = 0;
  for (std::size_t i = 0; i < f.voxels().size(); ++i) n += f.level(i, level).segment_count;
  return n;
}

double mean_luminance(const Image& img) {
  double sum = 0;
  for (std::size_t i = 0; i < img.rgba.size(); i += 4) sum += img.rgba[i] + img.rgba[i + 1] + img.rgba[i + 2];
  return sum / double(img.rgba.size() / 4);
}

TEST(LevelOpacity, ACoarseSegmentStandsForTheSegmentsItSamples) {
  EXPECT_FLOAT_EQ(SceneLayout::level_opacity(0.3f, 0), 0.3f);
  EXPECT_NEAR(1.0 - SceneLayout::level_opacity(0.05f, 1), std::pow(0.95, 8), 1e-6);
  EXPECT_NEAR(1.0 - SceneLayout::level_opacity(0.05f, 2), std::pow(0.95, 64), 1e-6);
  EXPECT_LE(SceneLayout::level_opacity(0.9f, 4), 1.0f);
}

// Level d uploads and draws its own segments only: about 1/8^d of them, all of its voxels' prefixes.
TEST_F(LevelsOfDetail, ACoarseLevelDrawsOnlyItsSegments) {
  const VxlFile f = file();
  ASSERT_EQ(f.level_count(), 4u);
  RenderSettings s;
  s.opacity = 0.05f;
  std::uint64_t previous_bytes = 0;
  for (std::uint32_t level = 0; level < 3; ++level) {
    Renderer r(f, 0, level);
    EXPECT_EQ(r.layout().level(), level);
    render_image(r, test::synth_brain_view(), s, 128, 128);
    EXPECT_EQ(r.stats().segments_drawn, level_segments(f, level)) << "level " << level;
    RenderSettings unsorted = s;  // the streamline-order draw: the level's voxlines only
    unsorted.mode = RenderMode::Unsorted;
    render_image(r, test::synth_brain_view(), unsorted, 128, 128);
    EXPECT_EQ(r.stats().segments_drawn, level_segments(f, level)) << "unsorted, level " << level;
    RenderSettings segsort = s;  // each voxel's level segments, sorted for the view
    segsort.mode = RenderMode::Segsort;
    render_image(r, test::synth_brain_view(), segsort, 128, 128);
    EXPECT_EQ(r.stats().segments_drawn, level_segments(f, level)) << "segsort, level " << level;
    if (level > 0) {
      EXPECT_LT(r.gpu_bytes() * 4, previous_bytes) << "level " << level;
    }
    previous_bytes = r.gpu_bytes();
  }
  EXPECT_LT(level_segments(f, 1) * 5, level_segments(f, 0));
  Renderer too_coarse(f, 0, 7);  // past the file's coarsest level: its coarsest
  EXPECT_EQ(too_coarse.layout().level(), 3u);
}

// With its opacity compensated, a coarse level keeps the picture's brightness; drawn with the full
// level's opacity it would be several times darker.
TEST_F(LevelsOfDetail, CompensatedOpacityKeepsTheBrightness) {
  const VxlFile f = file();
  RenderSettings s;
  s.opacity = 0.02f;
  Renderer full(f, 0, 0), coarse(f, 0, 1);
  const Image a = render_image(full, test::synth_brain_view(), s, 160, 160);
  const Image b = render_image(coarse, test::synth_brain_view(), s, 160, 160);
  const double la = mean_luminance(a), lb = mean_luminance(b);
  ASSERT_GT(la, 1.0) << "the scene is in view";
  EXPECT_NEAR(lb / la, 1.0, 0.2);
  RenderSettings uncompensated = s;
  uncompensated.opacity = s.opacity / 8;  // what the coarse level's opacity would have to undo
  const Image c = render_image(coarse, test::synth_brain_view(), uncompensated, 160, 160);
  EXPECT_LT(mean_luminance(c) / la, 0.5) << "the check can tell a missing compensation";
  EXPECT_GT(ssim_luminance(a, b), 0.5) << "a coarse level looks like the whole";
}

// The level chosen for a budget is the finest whose GPU copy fits it, and the copy (everything a mode can
// upload, the dataset order and the per-vertex attributes included) stays within it.
TEST_F(LevelsOfDetail, TheBudgetIsNeverExceeded) {
  const VxlFile f = file();
  const std::vector<const VxlFile*> files = {&f};
  const std::uint64_t full = SceneLayout(files, 1 << 27, 0).upload_bytes();
  const std::uint64_t one = SceneLayout(files, 1 << 27, 1).upload_bytes();
  EXPECT_EQ(SceneLayout::finest_level_within(files, 1 << 27, full), 0u);
  EXPECT_EQ(SceneLayout::finest_level_within(files, 1 << 27, full - 1), 1u);
  EXPECT_EQ(SceneLayout::finest_level_within(files, 1 << 27, one), 1u);
  EXPECT_EQ(SceneLayout::finest_level_within(files, 1 << 27, one - 1), 2u);
  try {
    SceneLayout::finest_level_within(files, 1 << 27, 1000);
    FAIL() << "a 1000-byte budget fits";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    EXPECT_NE(std::string(e.what()).find("even at its coarsest level of detail (3)"), std::string::npos) << e.what();
  }

  for (std::uint64_t budget : {full, (full + one) / 2, one / 3}) {
    const std::uint32_t level = SceneLayout::finest_level_within(files, 1 << 27, budget);
    Renderer r(f, 1 << 27, level);
    RenderSettings s;
    s.mode = RenderMode::Unsorted;  // uploads the dataset order
    r.prepare(RenderMode::Unsorted);
    s.color = ColorMode::Group;  // uploads the per-vertex attributes
    render_image(r, test::synth_brain_view(), s, 64, 64);
    EXPECT_LE(r.gpu_bytes(), budget) << "budget " << budget << ", level " << level;
    EXPECT_LE(r.gpu_bytes(), r.layout().upload_bytes());
    s.mode = RenderMode::Segsort;  // its view order replaces the dataset order in the same buffers
    render_image(r, test::synth_brain_view(), s, 64, 64);
    EXPECT_LE(r.gpu_bytes(), budget) << "segsort, budget " << budget << ", level " << level;
  }
}

// A level smaller than the texture limit allows fits where full detail does not: the limit caps the level
// drawn, not the tractogram that can be opened.
TEST_F(LevelsOfDetail, ATextureLimitTooSmallForFullDetailLeavesACoarserLevel) {
  const VxlFile f = file();
  const std::vector<const VxlFile*> files = {&f};
  // Not even the largest voxel fits at full detail.
  const std::uint64_t texels = SceneLayout::largest_voxel_texels(files) / 2;
  EXPECT_THROW(SceneLayout(files, texels, 0), Error);
  const std::uint32_t level = SceneLayout::finest_level_within(files, texels, ~0ull);
  EXPECT_GT(level, 0u);
  Renderer r(f, texels, level);
  RenderSettings s;
  s.opacity = 0.05f;
  EXPECT_GT(test::lit_pixels(render_image(r, test::synth_brain_view(), s, 96, 96)), 500);
}

// A budget below 1 MiB is not reported as "0 MiB" on both sides ("needs 0 MiB ... budget of 0 MiB"): small
// sizes are given in bytes.
TEST_F(LevelsOfDetail, ABudgetNoLevelFitsSaysBothSizesInBytes) {
  const VxlFile f = file();
  const std::vector<const VxlFile*> files = {&f};
  const std::uint32_t coarsest = SceneLayout::coarsest_level(files);
  const std::uint64_t needs = SceneLayout(files, ~0ull, coarsest).upload_bytes();
  ASSERT_LT(needs, 1u << 20);
  try {
    (void)SceneLayout::finest_level_within(files, ~0ull, 1);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    const std::string m = e.what();
    EXPECT_NE(m.find("GPU memory budget of 1 bytes"), std::string::npos) << m;
    EXPECT_NE(m.find("needs " + std::to_string(needs) + " bytes of GPU memory"), std::string::npos) << m;
    EXPECT_EQ(m.find(" 0 MiB"), std::string::npos) << m;
  }
}

// voxview says which level it draws and why, and refuses a budget no level fits (exit 4, unsupported)
// without writing a picture.
TEST_F(LevelsOfDetail, VoxviewDrawsTheFinestLevelItsBudgetAllows) {
  const VxlFile f = file();
  const std::vector<const VxlFile*> files = {&f};
  const std::uint64_t full = SceneLayout(files, 1 << 27, 0).upload_bytes();
  const std::string png = dir.file("out.png"), scene = dir.file("scene.vxl");
  auto voxview = [&](const std::string& args) {
    return test::run_program(VOXVIEW_CLI, "'" + scene + "' --render '" + png + "' --size 64x64 " + args);
  };
  auto r = voxview("--gpu-memory " + std::to_string(full - 1));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("drawing level 1 (of levels 0 to 3; about 1/8 of the streamlines"), std::string::npos)
      << r.output;
  EXPECT_TRUE(std::filesystem::exists(png));
  std::filesystem::remove(png);
  r = voxview("--gpu-memory " + std::to_string(full));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("drawing level"), std::string::npos) << r.output;
  r = voxview("--level 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(
      r.output.find(
          "drawing level 2 (of levels 0 to 3; about 1/64 of the streamlines, opacity compensated) as --level asks"),
      std::string::npos)
      << r.output;
  std::filesystem::remove(png);
  r = voxview("--level 5");  // past the coarsest: the coarsest, saying so
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("drawing level 3 (of levels 0 to 3; about 1/512 of the streamlines, opacity compensated): "
                          "--level 5 is past the coarsest level the files have"),
            std::string::npos)
      << r.output;
  std::filesystem::remove(png);
  r = voxview("--gpu-memory 1K");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("does not fit the GPU memory budget of"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(png));
}

// 10M-class behaviour at a small scale: a budget that holds only a coarse level of the whole scene still
// draws a thin slab of it in full detail, since only the spans the slab's voxels lie in are uploaded.
TEST_F(LevelsOfDetail, VoxviewDrawsAThinSlabInFullDetailUnderABudgetTooSmallForTheWhole) {
  const VxlFile f = file();
  const std::vector<const VxlFile*> files = {&f};
  const std::uint64_t texels = std::max<std::uint64_t>(4096, SceneLayout::largest_voxel_texels(files));
  const std::uint64_t full = SceneLayout(files, texels, 0).upload_bytes();
  const std::string scene = dir.file("scene.vxl");
  auto voxview = [&](const std::string& png, const std::string& args) {
    return test::run_program(VOXVIEW_CLI, "'" + scene + "' --render '" + dir.file(png) +
                                              "' --size 96x96 --view axial --slab 4 --span-texels 4096 " + args);
  };
  auto r = voxview("budget.png", "--gpu-memory " + std::to_string(full / 2));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("drawing level 0: the visible part fits the GPU memory budget"), std::string::npos)
      << r.output;
  r = voxview("whole.png", "--level 0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image budget = read_image(dir.file("budget.png")), whole = read_image(dir.file("whole.png"));
  EXPECT_GT(test::lit_pixels(whole), 200);
  EXPECT_EQ(compare_images(budget, whole).differing_pixels, 0u) << "every visible voxel drawn, at full detail";
  // Without the slab the same budget takes a coarser level.
  r = test::run_program(VOXVIEW_CLI, "'" + scene + "' --render '" + dir.file("all.png") +
                                         "' --size 96x96 --view axial --span-texels 4096 --gpu-memory " +
                                         std::to_string(full / 2));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("drawing level 1"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace vxl
