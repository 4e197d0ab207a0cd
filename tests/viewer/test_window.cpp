// The interactive `voxview FILE` window, driven by its automation options (--frames, --screenshot) under a
// virtual X server (xvfb-run; skipped where it is not installed), and the window's voxel-grid overlay,
// drawn headless.
#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/test_support.h"
#include "tests/viewer/render_support.h"
#include "viewer/app/focus_copy.h"
#include "viewer/platform/image_io.h"
#include "viewer/platform/image_metrics.h"
#include "viewer/render/grid_overlay.h"
#include "viewer/render/scene_layout.h"

namespace vxl {
namespace {

using test::CommandResult;
using test::ScratchDir;

bool have_xvfb_run() { return std::system("command -v xvfb-run >/dev/null 2>&1") == 0; }

CommandResult run_shell(const std::string& command) {
  CommandResult r{-1, {}};
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return r;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.output.append(buf, n);
  const int status = ::pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

std::string shell_quoted(const std::string& s) { return "'" + s + "'"; }

// voxview under a fresh virtual X server (-a: a free display number, so tests may run side by side).
CommandResult run_voxview_in_xvfb(const std::string& args) {
  return run_shell("xvfb-run -a -s \"-screen 0 800x600x24\" " + shell_quoted(VOXVIEW_CLI) + " " + args);
}

bool uniform(const Image& img) {
  for (std::size_t i = 4; i < img.rgba.size(); ++i)
    if (img.rgba[i] != img.rgba[i % 4]) return false;
  return true;
}

using test::lit_pixels;

#define VXL_REQUIRE_XVFB()                                                                                   \
  do {                                                                                                       \
    if (!have_xvfb_run()) GTEST_SKIP() << "xvfb-run is not installed (apt install xvfb xauth): no X server"; \
  } while (0)

class Window : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_STRNE(VOXVIEW_CLI, "") << "VOXVIEW_CLI is empty: the voxview target was not known to tests/CMakeLists.txt";
    ASSERT_TRUE(std::filesystem::exists(VOXVIEW_CLI)) << VOXVIEW_CLI << " is not built";
  }

  // A synthetic tractogram from the project's own generator, as .tck and converted to .vxl (with the
  // default levels of detail).
  void make_inputs(int streamlines = 300) {
    CommandResult synth =
        test::run_cli("synth --streamlines " + std::to_string(streamlines) + " --seed 7 " + shell_quoted(tck));
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    CommandResult convert = test::run_cli("convert --voxel-size 10 " + shell_quoted(tck) + " " + shell_quoted(vxl));
    ASSERT_EQ(convert.exit_code, 0) << convert.output;
  }

  // Focus first's scene: 6000 streamlines under a GPU memory budget that holds only level 1 of the whole scene
  // (`args`: the window size, view and budget), and a sphere of 8 mm at a point of some streamline, moved `dx` mm
  // along x (at dx = 0 it selects a bundle).
  struct BudgetScene {
    std::string args;
    std::array<float, 3> point;
    std::string sphere_at(double dx) const {
      return std::to_string(point[0] + dx) + "," + std::to_string(point[1]) + "," + std::to_string(point[2]) + ",8";
    }
  };
  BudgetScene budget_scene() {
    make_inputs(6000);
    const VxlFile f = VxlFile::open(vxl);
    const std::vector<const VxlFile*> files = {&f};
    const std::uint64_t texels = std::max<std::uint64_t>(4096, SceneLayout::largest_voxel_texels(files));
    const std::vector<float> points = f.all_vertices();
    const std::size_t middle = points.size() / 6 * 3;
    return {" --size 200x150 --view axial --span-texels 4096 --gpu-memory " +
                std::to_string(SceneLayout(files, texels, 1).upload_bytes()),
            {points[middle], points[middle + 1], points[middle + 2]}};
  }

  // Runs the window on the .vxl with `args` and --stats; returns what it wrote (null when it wrote nothing).
  nlohmann::json window_stats(const std::string& args) {
    const std::string stats = dir.file("stats.json");
    CommandResult r = run_voxview_in_xvfb(shell_quoted(vxl) + " " + args + " --stats " + shell_quoted(stats));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(stats);
    if (!in) {
      ADD_FAILURE() << "no stats file: " << r.output;
      return nullptr;
    }
    return nlohmann::json::parse(in);
  }

  Image window_screenshot(const std::string& input) {
    const std::string png = dir.file("shot.png");
    std::filesystem::remove(png);
    CommandResult r =
        run_voxview_in_xvfb(shell_quoted(input) + " --frames 5 --screenshot " + shell_quoted(png) + " --size 320x240");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    if (!std::filesystem::exists(png)) {
      ADD_FAILURE() << "no screenshot: " << r.output;
      return {};
    }
    Image img = read_image(png);
    EXPECT_EQ(img.width, 320);
    EXPECT_EQ(img.height, 240);
    EXPECT_FALSE(uniform(img));
    EXPECT_GT(lit_pixels(img), 320 * 240 / 100) << "the tractogram should cover more than 1% of the picture";
    return img;
  }

  ScratchDir dir;
  std::string tck = dir.file("synth.tck");
  std::string vxl = dir.file("synth.vxl");
};

TEST_F(Window, ShowsAVxlFileAndSavesTheLastFrameWithoutThePanel) {
  VXL_REQUIRE_XVFB();
  make_inputs();
  Image shot = window_screenshot(vxl);
  ASSERT_EQ(shot.width, 320);
  // The same first frame headless: the window starts with the same camera and renderer, and the automated
  // screenshot leaves the panel out, so the pictures agree but for rasteriser details.
  const std::string headless = dir.file("headless.png");
  CommandResult r = run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) + " --render " +
                              shell_quoted(headless) + " --size 320x240");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Measured on llvmpipe 15: 2 pixels differed with the line shader of before colour-by-value, 1264 (1.65%)
  // with it (the same lines, some moved by a pixel: the colour branch changes the vertex shader's code, and
  // the GLX and EGL paths round positions differently). The mean error separates that from a wrong picture:
  // 2.7e-5 here, 1.2e-4 for `basic` instead of `axis`, 1.5e-3 for opacity 0.25 instead of 0.3, 5e-3 for the
  // azimuth 1 degree off.
  ImageDiff d = compare_images(shot, read_image(headless));
  EXPECT_LT(d.differing_pixels, 320u * 240u * 25u / 1000u)
      << "mean error " << d.mean_error << ", max at " << d.max_x << "," << d.max_y;
  EXPECT_LT(d.mean_error, 6e-5);
}

TEST_F(Window, AViewSavedInTheWindowReplaysHeadless) {
  VXL_REQUIRE_XVFB();
  make_inputs();
  const std::string view = dir.file("view.json"), shot = dir.file("window.png"), replay = dir.file("replay.png");
  CommandResult w = run_voxview_in_xvfb(shell_quoted(vxl) +
                                        " --frames 3 --size 200x150 --view 40,15 --lighting --slab 60 --opacity 0.6"
                                        " --save-camera " +
                                        shell_quoted(view) + " --screenshot " + shell_quoted(shot));
  ASSERT_EQ(w.exit_code, 0) << w.output;
  ASSERT_TRUE(std::filesystem::exists(view)) << w.output;
  CommandResult h = run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) + " --camera " + shell_quoted(view) +
                              " --render " + shell_quoted(replay));
  ASSERT_EQ(h.exit_code, 0) << h.output;
  const Image a = read_image(shot), b = read_image(replay);
  ASSERT_EQ(b.width, 200);
  ASSERT_EQ(b.height, 150);
  // Same camera, settings and size; window (GLX) and headless (EGL) rasterise alike but for details.
  ImageDiff d = compare_images(a, b);
  EXPECT_LT(d.differing_pixels, 200u * 150u / 100u) << "mean error " << d.mean_error;
  EXPECT_GT(lit_pixels(b), 200 * 150 / 200);
}

// A scripted orbit under a frame budget too small for full detail: every moving frame is drawn at a
// coarser level, the last one (at rest) at the scene's own level, and --stats reports them.
TEST_F(Window, MovingFramesDrawACoarserLevelWithinTheFrameBudget) {
  VXL_REQUIRE_XVFB();
  make_inputs(3000);
  const std::string png = dir.file("shot.png");
  const nlohmann::json j =
      window_stats("--size 320x240 --frames 6 --orbit 10 --frame-budget 0.001 --screenshot " + shell_quoted(png));
  ASSERT_FALSE(j.is_null());
  const auto& frames = j.at("frames");
  ASSERT_EQ(frames.size(), 6u);
  EXPECT_EQ(frames[0].at("moving"), false);  // nothing to compare the first view with
  EXPECT_EQ(frames[0].at("level"), 0);
  for (std::size_t i = 1; i + 1 < frames.size(); ++i) {
    EXPECT_EQ(frames[i].at("moving"), true) << i;
    EXPECT_GT(frames[i].at("level").get<int>(), 0) << "a 1 us budget is never met at full detail; frame " << i;
  }
  EXPECT_EQ(frames.back().at("moving"), false);
  EXPECT_EQ(frames.back().at("level"), 0);
  EXPECT_EQ(j.at("moving_frames"), 4);
  EXPECT_GT(j.at("first_picture_s").get<double>(), 0.0);
  // On screen after it was drawn (the swap that shows it), and after the window and the viewer were made.
  const auto& startup = j.at("startup");
  EXPECT_GE(startup.at("main_s").get<double>(), 0.0);
  EXPECT_GE(startup.at("window_open_s").get<double>(), startup.at("main_s").get<double>());
  EXPECT_GT(startup.at("window_open_s").get<double>(), 0.0);
  EXPECT_GE(startup.at("viewer_ready_s").get<double>(), startup.at("window_open_s").get<double>());
  EXPECT_GE(j.at("first_picture_s").get<double>(), startup.at("viewer_ready_s").get<double>());
  EXPECT_GT(j.at("first_on_screen_s").get<double>(), j.at("first_picture_s").get<double>());
  EXPECT_LT(j.at("first_on_screen_s").get<double>(), frames[1].at("since_start_s").get<double>());
  EXPECT_EQ(startup.at("first_on_screen_s"), j.at("first_on_screen_s"));
  // The levels drawn were uploaded: their bytes and the time that took.
  const auto& upload = j.at("upload");
  EXPECT_GT(upload.at("bytes").get<std::uint64_t>(), 0u);
  EXPECT_GE(upload.at("spans").get<std::uint64_t>(), 2u) << "full detail and at least one coarser level";
  EXPECT_GT(upload.at("seconds").get<double>(), 0.0);
  EXPECT_GT(upload.at("gb_per_s").get<double>(), 0.0);
  // The summary comes first and the frames' list last, so that the start of the file says the most.
  const std::string text = vxl::test::slurp<std::string>(dir.file("stats.json"));
  EXPECT_LT(text.find("\"first_on_screen_s\""), text.find("\"frames\"")) << text;
  EXPECT_LT(text.find("\"upload\""), text.find("\"frames\"")) << text;
  EXPECT_LT(text.find("\"moving_p95_ms\""), text.find("\"frames\"")) << text;
  EXPECT_EQ(j.at("full_detail_s"), frames[0].at("since_start_s"));
  EXPECT_GT(j.at("moving_p95_ms").get<double>(), 0.0);
  EXPECT_GE(j.at("moving_p95_ms").get<double>(), j.at("moving_median_ms").get<double>());
  EXPECT_GT(lit_pixels(read_image(png)), 320 * 240 / 100) << "the last frame, at rest, shows the scene";
}

// A scene of more than a million segments shows a coarse level first; at rest, full detail follows in
// pieces that each fit the frame budget (the coarse picture stays on screen meanwhile).
TEST_F(Window, TheFirstPictureIsCoarseAndFullDetailFollowsInPieces) {
  VXL_REQUIRE_XVFB();
  make_inputs(30000);
  const nlohmann::json j = window_stats("--size 320x240 --frames 1 --until-refined --no-exact-when-still");
  ASSERT_FALSE(j.is_null());
  const auto& frames = j.at("frames");
  ASSERT_GE(frames.size(), 3u);
  EXPECT_EQ(frames[0].at("level"), 1) << "1.6M segments at full detail, 200k at level 1";
  EXPECT_EQ(frames[0].at("work"), "whole");
  EXPECT_EQ(j.at("first_picture_s"), frames[0].at("since_start_s"));
  for (std::size_t i = 1; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].at("work"), "full-detail piece") << i;
    EXPECT_EQ(frames[i].at("level"), 0) << i;
    EXPECT_EQ(frames[i].at("moving"), false) << i;
    EXPECT_EQ(frames[i].at("completes"), i + 1 == frames.size()) << "only the last piece completes; frame " << i;
  }
  // The first piece assumes 1000 segments a millisecond: 100k of the 1.6M segments in the default 100 ms.
  EXPECT_GE(j.at("refinement_pieces").get<int>(), 2);
  EXPECT_EQ(j.at("full_detail_s"), frames.back().at("since_start_s"));
  EXPECT_EQ(j.at("exact_s"), -1) << "--no-exact-when-still";
}

// A first picture two levels coarse is refined through the level between: level 1 is drawn in pieces and shown
// once complete (an eighth of full detail's segments), then full detail follows in its own pieces.
TEST_F(Window, AtRestEachLevelOnTheWayToFullDetailIsShown) {
  VXL_REQUIRE_XVFB();
  make_inputs(50000);
  const nlohmann::json j = window_stats("--size 320x240 --frames 1 --until-refined --no-exact-when-still");
  ASSERT_FALSE(j.is_null());
  const auto& frames = j.at("frames");
  ASSERT_GE(frames.size(), 3u);
  EXPECT_EQ(frames[0].at("level"), 2) << "2.7M segments at full detail, 340k at level 1, 42k at level 2";
  // Each piece draws the level after the last one shown: level 1 until it completes, then level 0.
  std::vector<int> completed;
  int expected = 1;
  for (std::size_t i = 1; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].at("work"), "full-detail piece") << i;
    EXPECT_EQ(frames[i].at("level"), expected) << i;
    if (frames[i].at("completes").get<bool>()) completed.push_back(expected--);
  }
  EXPECT_EQ(completed, (std::vector<int>{1, 0})) << "level 1 shown, then full detail";
  EXPECT_EQ(j.at("full_detail_s"), frames.back().at("since_start_s"));
}

// While the level refined to is uploading (small spans: a few a frame, the nearest first), a partial picture shows
// the spans in so far with the level on screen standing in for the others; the complete level follows, and it is the
// picture drawn without partial pictures. (`always`: by default a partial picture waits until the upload has taken as
// long as it would take to draw, which on a software renderer is seldom.)
TEST_F(Window, PartialPicturesShowTheSpansInWhileALevelUploads) {
  VXL_REQUIRE_XVFB();
  make_inputs(6000);
  const std::string args = "--size 200x150 --span-texels 4096 --frames 1 --until-refined --no-exact-when-still";
  const std::string never_png = dir.file("never.png"), always_png = dir.file("always.png");
  const nlohmann::json never = window_stats(args + " --partial-pictures never --screenshot " + shell_quoted(never_png));
  const nlohmann::json always =
      window_stats(args + " --partial-pictures always --screenshot " + shell_quoted(always_png));
  ASSERT_FALSE(never.is_null());
  ASSERT_FALSE(always.is_null());
  for (const auto& f : never.at("frames")) EXPECT_NE(f.at("work"), "partial piece");

  const auto& frames = always.at("frames");
  ASSERT_GE(frames.size(), 3u);
  EXPECT_EQ(frames[0].at("level"), 1) << "a coarse first picture";
  // Each partial picture draws some voxels from the level arriving and the others from the level on screen, more of
  // them from the level arriving as its spans come in.
  std::vector<std::uint64_t> voxels_in;
  for (std::size_t i = 1; i + 1 < frames.size(); ++i) {
    EXPECT_EQ(frames[i].at("level"), 0) << i;
    if (frames[i].at("work") != "partial piece") continue;
    EXPECT_LT(frames[i].at("since_start_s").get<double>(), always.at("full_detail_s").get<double>()) << i;
    if (!frames[i].at("completes").get<bool>()) continue;
    voxels_in.push_back(frames[i].at("voxels_in").get<std::uint64_t>());
    EXPECT_GT(voxels_in.back(), 0u) << i;
    EXPECT_GT(frames[i].at("voxels_standing_in").get<std::uint64_t>(), 0u) << i;
  }
  ASSERT_GE(voxels_in.size(), 2u) << "the level arrives over many frames: several partial pictures";
  EXPECT_TRUE(std::is_sorted(voxels_in.begin(), voxels_in.end()));
  EXPECT_LT(voxels_in.front(), voxels_in.back());
  EXPECT_EQ(frames.back().at("work"), "full-detail piece");
  EXPECT_EQ(frames.back().at("completes"), true);
  EXPECT_EQ(always.at("full_detail_s"), frames.back().at("since_start_s")) << "a partial picture is not full detail";
  EXPECT_EQ(compare_images(read_image(never_png), read_image(always_png)).differing_pixels, 0u);
}

// At rest, once full detail is on screen, the axis mode goes on to the exact picture, run by run; it is
// what headless --mode exact draws (but for a few pixels at voxel faces between runs).
TEST_F(Window, ExactArrivesWhenTheCameraIsStill) {
  VXL_REQUIRE_XVFB();
  make_inputs(3000);
  const std::string png = dir.file("still.png");
  const nlohmann::json j =
      window_stats("--size 200x150 --frames 1 --until-refined --frame-budget 5 --screenshot " + shell_quoted(png));
  ASSERT_FALSE(j.is_null());
  const auto& frames = j.at("frames");
  ASSERT_GE(frames.size(), 3u);
  EXPECT_EQ(frames[0].at("level"), 0) << "a small scene: full detail at once";
  EXPECT_EQ(frames.back().at("work"), "exact piece");
  EXPECT_EQ(frames.back().at("completes"), true);
  EXPECT_GE(frames.size(), 3u) << "a 5 ms budget splits exact into several runs";
  EXPECT_GT(j.at("exact_s").get<double>(), j.at("full_detail_s").get<double>());
  EXPECT_GE(j.at("piece_p95_ms").get<double>(), j.at("piece_median_ms").get<double>());

  auto headless = [&](const std::string& mode) {
    const std::string out = dir.file(mode + ".png");
    CommandResult h = run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) + " --size 200x150 --mode " + mode +
                                " --render " + shell_quoted(out));
    EXPECT_EQ(h.exit_code, 0) << h.output;
    return read_image(out);
  };
  const Image still = read_image(png), exact = headless("exact"), axis = headless("axis");
  ASSERT_GT(lit_pixels(exact), 200 * 150 / 100);
  EXPECT_LT(score_image(still, exact).rmse, 0.6 * score_image(axis, exact).rmse)
      << "the window's picture at rest is the exact one, not axis";
}

// The window shows the selection's regions as shells by default, through its refinement in pieces up to
// exact: at rest its picture is the headless one with --show-regions, not the one without.
TEST_F(Window, RegionShellsAreShownAtRest) {
  VXL_REQUIRE_XVFB();
  make_inputs();
  const std::string selection = " --size 200x150 --include 0,0,0,30 --context-opacity 0.3";
  const std::string png = dir.file("regions.png");
  const nlohmann::json j = window_stats(selection + " --frames 1 --until-refined --screenshot " + shell_quoted(png));
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j.at("frames").back().at("work"), "exact piece");
  auto headless = [&](const std::string& name, const std::string& extra) {
    const std::string out = dir.file(name);
    CommandResult h = run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) + selection +
                                " --mode exact --render " + shell_quoted(out) + extra);
    EXPECT_EQ(h.exit_code, 0) << h.output;
    return read_image(out);
  };
  const Image still = read_image(png), shown = headless("shown.png", " --show-regions"),
              plain = headless("plain.png", "");
  const double to_plain = score_image(plain, shown).rmse;
  ASSERT_GT(to_plain, 0) << "the shell changes the picture";
  EXPECT_LT(score_image(still, shown).rmse, 0.5 * to_plain) << "the window at rest shows the shells";
}

// At rest the window refines to the finest level whose visible part fits the GPU memory budget: under a
// budget that holds only level 1 of the whole scene, a thin slab comes at full detail, as headless draws it.
TEST_F(Window, AtRestAThinSlabIsRefinedToFullDetailUnderABudgetForLevelOne) {
  VXL_REQUIRE_XVFB();
  make_inputs(12000);
  const VxlFile f = VxlFile::open(vxl);
  const std::vector<const VxlFile*> files = {&f};
  const std::uint64_t texels = std::max<std::uint64_t>(4096, SceneLayout::largest_voxel_texels(files));
  const std::string budget = std::to_string(SceneLayout(files, texels, 0).upload_bytes() / 2);
  const std::string view = " --size 200x150 --view axial --slab 4 --span-texels 4096 --gpu-memory " + budget;
  const std::string png = dir.file("slab.png"), reference = dir.file("reference.png");
  const nlohmann::json j =
      window_stats(view + " --frames 1 --until-refined --no-exact-when-still --screenshot " + shell_quoted(png));
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j.at("scene_level"), 1) << "the whole scene fits the budget at level 1";
  const auto& frames = j.at("frames");
  ASSERT_GE(frames.size(), 2u);
  EXPECT_EQ(frames.back().at("work"), "full-detail piece");
  EXPECT_EQ(frames.back().at("level"), 0) << "the slab's spans fit at full detail";
  EXPECT_EQ(frames.back().at("completes"), true);
  EXPECT_EQ(j.at("full_detail_s"), frames.back().at("since_start_s"));
  CommandResult h =
      run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) + view + " --render " + shell_quoted(reference));
  ASSERT_EQ(h.exit_code, 0) << h.output;
  EXPECT_NE(h.output.find("drawing level 0: the visible part fits"), std::string::npos) << h.output;
  const Image a = read_image(png), b = read_image(reference);
  ASSERT_GT(lit_pixels(b), 200 * 150 / 100);
  EXPECT_LT(compare_images(a, b).differing_pixels, 200u * 150u / 100u) << "the window's picture at rest is headless'";
}

// Focus first in the window: under a GPU memory budget that holds only level 1 of the whole scene, the
// selection's focus is drawn at full detail (its copy, written off the window's thread) and the context at
// level 1, as headless draws it; --stats says so per frame (focus_level).
TEST_F(Window, UnderABudgetTheFocusIsDrawnAtFullDetailAsHeadless) {
  VXL_REQUIRE_XVFB();
  const BudgetScene scene = budget_scene();
  const std::string args = scene.args + " --include=" + scene.sphere_at(0) +
                           " --context-opacity 0.1 --focus-opacity 1 --color group --group selected=#ff0000";
  const std::string png = dir.file("window.png"), reference = dir.file("headless.png");
  const nlohmann::json j =
      window_stats(args + " --frames 3 --until-refined --no-exact-when-still --screenshot " + shell_quoted(png));
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j.at("scene_level"), 1);
  const auto& last = j.at("frames").back();
  EXPECT_GE(last.at("level"), 1) << "the context below full detail";
  ASSERT_TRUE(last.contains("focus_level")) << j.dump();
  EXPECT_EQ(last.at("focus_level"), 0);
  CommandResult h =
      run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) + args + " --render " + shell_quoted(reference));
  ASSERT_EQ(h.exit_code, 0) << h.output;
  EXPECT_NE(h.output.find("focus at level 0 and context at level " + std::to_string(int(last.at("level")))),
            std::string::npos)
      << h.output;
  const Image a = read_image(png), b = read_image(reference);
  ASSERT_GT(lit_pixels(b), 200 * 150 / 100);
  EXPECT_LT(compare_images(a, b).differing_pixels, 200u * 150u / 100u) << "the window's picture is headless'";
}

// A scripted drag under the same budget: after its last step the window waits, drawing frames, for the last
// position's selection and its focus copy (both made off the window's thread), then draws its last picture with
// the focus at full detail, as a window started with the sphere at that position draws it; --stats says that it
// waited and how long.
TEST_F(Window, AScriptedDragUnderABudgetEndsWithTheFocusCopyOfItsLastPosition) {
  VXL_REQUIRE_XVFB();
  const BudgetScene scene = budget_scene();
  const std::string args = scene.args + " --context-opacity 0 --focus-opacity 1 --color group --group selected=#ff0000";
  // --frames 6 moves the sphere on frames 1 to 5: 5 steps of 2 mm along x.
  const std::string dragged = dir.file("dragged.png"), still = dir.file("still.png");
  const nlohmann::json j = window_stats(args + " --include=" + scene.sphere_at(0) +
                                        " --drag-region 2,0,0 --frames 6 --screenshot " + shell_quoted(dragged));
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j.at("scene_level"), 1);
  const auto& last = j.at("frames").back();
  EXPECT_EQ(last.at("level"), 1);
  ASSERT_TRUE(last.contains("focus_level")) << "the last picture without the focus copy: " << j.dump();
  EXPECT_EQ(last.at("focus_level"), 0);
  ASSERT_TRUE(j.contains("drag_end_wait")) << j.dump();
  const auto& wait = j.at("drag_end_wait");
  EXPECT_TRUE(wait.at("waited").get<bool>()) << "the copy takes longer than a frame";
  EXPECT_GT(wait.at("ms").get<double>(), 0.0);
  EXPECT_FALSE(wait.at("timed_out").get<bool>());
  // Nothing is refined while the copy is on its way (its picture would be drawn again): no refinement piece comes
  // before the first picture with the copy.
  bool refined = false;
  for (const nlohmann::json& f : j.at("frames")) {
    if (f.contains("focus_level")) {
      EXPECT_FALSE(refined) << "a refinement piece was drawn while the focus copy was on its way: " << j.dump();
      break;
    }
    refined |= f.value("work", std::string("whole")) != "whole";
  }
  // While the sphere moves, a selection searches only the streamlines of the level the moving frames draw (their
  // pictures need no more); the one the drag's end waits for searches every streamline, and its focus is what
  // the last picture, compared below, shows.
  const auto& searched = j.at("selection_level");
  ASSERT_EQ(searched.size(), j.at("selections").get<std::size_t>());
  EXPECT_EQ(searched.back().get<int>(), 0) << j.dump();
  int moving_level = 0, level_searched = 0;
  for (const nlohmann::json& f : j.at("frames"))
    if (f.at("moving").get<bool>()) moving_level = std::max(moving_level, f.at("level").get<int>());
  for (const auto& level : searched) level_searched = std::max(level_searched, level.get<int>());
  ASSERT_GT(moving_level, 0) << "the moving frames draw a coarser level: " << j.dump();
  EXPECT_GT(level_searched, 0) << j.dump();
  EXPECT_LE(level_searched, moving_level) << j.dump();
  EXPECT_EQ(j.at("full_selections").get<int>(), std::count(searched.begin(), searched.end(), 0));
  CommandResult r = run_voxview_in_xvfb(shell_quoted(vxl) + args + " --include=" + scene.sphere_at(10) +
                                        " --frames 3 --screenshot " + shell_quoted(still));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image a = read_image(dragged), b = read_image(still);
  ASSERT_GT(lit_pixels(b), 200 * 150 / 200);
  // Without the wait the last picture draws the focus at level 1: about 40 % of its pixels differ.
  EXPECT_LT(compare_images(a, b).differing_pixels, 200u * 150u / 1000u)
      << "the drag's last picture is the focus of its last position at full detail (of " << lit_pixels(b) << ")";
}

TEST_F(Window, OpensATckDirectly) {
  VXL_REQUIRE_XVFB();
  make_inputs();
  window_screenshot(tck);
}

TEST_F(Window, EveryModeRunsInTheWindow) {
  VXL_REQUIRE_XVFB();
  make_inputs();
  for (const char* mode : {"opaque", "unsorted", "additive", "wboit", "basic", "axis", "segsort", "exact"}) {
    SCOPED_TRACE(mode);
    const std::string png = dir.file(std::string(mode) + ".png");
    CommandResult r =
        run_voxview_in_xvfb(shell_quoted(vxl) + " --mode " + mode + " --ortho --view axial --frames 2 --screenshot " +
                            shell_quoted(png) + " --size 160x120");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    Image img = read_image(png);
    EXPECT_EQ(img.width, 160);
    EXPECT_FALSE(uniform(img));
  }
}

TEST_F(Window, WithoutADisplaySaysHowToRenderHeadless) {
  make_inputs();
  CommandResult r = run_shell("env -u DISPLAY -u WAYLAND_DISPLAY " + shell_quoted(VOXVIEW_CLI) + " " +
                              shell_quoted(vxl) + " --frames 1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("cannot open a window"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--render"), std::string::npos) << r.output;
}

// Two short streamlines 200 mm apart along x, in 10 mm voxels. The grid origin is the bounds' minimum,
// (1, 1, 0) + offset, so the first lies in voxel (0, 0, 0) spanning x, y in [1, 11] and the second in (20, 0, 0).
Tractogram two_voxels(double offset) {
  Tractogram t;
  auto add = [&](std::initializer_list<double> xyz) {
    std::vector<float> p;
    for (double v : xyz) p.push_back(static_cast<float>(v + offset));
    t.add_streamline(p.data(), p.size() / 3);
  };
  add({1, 1, 0, 9, 5, 0});
  add({201, 1, 0, 209, 5, 0});
  t.source.path = "two_voxels";
  return t;
}

// Looking down on the first voxel, 1 mm per pixel on 64 x 64: the cube's sides x = 1, 11 and y = 11, 1
// fall on the centres of columns 26, 36 and rows 27, 37.
Camera above_first_voxel(double offset) {
  Camera c;
  c.target = glm::dvec3(6.5, 6.5, 5.0) + offset;
  c.orthographic = true;
  c.ortho_height = 64;
  c.distance = 100;
  auto v = *parse_view("axial");
  c.azimuth_deg = v[0];
  c.elevation_deg = v[1];
  return c;
}

Image overlay_image(Renderer& r, GridOverlay& grid, const Camera& camera, GridOverlay::Scope scope) {
  OffscreenTarget target(64, 64);
  target.bind();
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  grid.draw(r, camera, 1.0, scope, glm::vec4(1.0f));
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  return Image{64, 64, target.read_rgba()};
}

bool white(const Image& img, int x, int y) {
  const std::uint8_t* p = img.pixel(x, y);
  return p[0] == 255 && p[1] == 255 && p[2] == 255;
}

class WindowGridOverlay : public ::testing::Test {
 protected:
  void SetUp() override { test::gl_context(); }
  ScratchDir dir;
};

TEST_F(WindowGridOverlay, OutlinesTheVoxelCubesWhereTheGridPutsThem) {
  for (double offset : {0.0, 1e5}) {
    SCOPED_TRACE(offset);
    VxlFile f = test::make_scene(dir, two_voxels(offset), 10.0, "grid" + std::to_string(int(offset)) + ".vxl");
    Renderer r(f);
    GridOverlay grid(r);
    Image img = overlay_image(r, grid, above_first_voxel(offset), GridOverlay::Scope::Drawn);
    for (auto [x, y] : {std::pair{26, 32}, {36, 32}, {31, 27}, {31, 37}, {26, 27}, {36, 37}})
      EXPECT_TRUE(white(img, x, y)) << "cube side at " << x << "," << y;
    for (auto [x, y] : {std::pair{31, 32}, {25, 32}, {37, 32}, {31, 26}, {31, 38}, {10, 10}})
      EXPECT_FALSE(white(img, x, y)) << "nothing at " << x << "," << y;
  }
}

TEST_F(WindowGridOverlay, DrawnScopeKeepsOnlyTheVoxelsInView) {
  VxlFile f = test::make_scene(dir, two_voxels(0.0), 10.0);
  Renderer r(f);
  GridOverlay grid(r);
  overlay_image(r, grid, above_first_voxel(0.0), GridOverlay::Scope::Drawn);
  EXPECT_EQ(grid.cubes_drawn(), 1u);
  overlay_image(r, grid, above_first_voxel(0.0), GridOverlay::Scope::All);
  EXPECT_EQ(grid.cubes_drawn(), 2u);
  Camera wide = above_first_voxel(0.0);
  wide.target.x = 105;
  wide.ortho_height = 300;
  overlay_image(r, grid, wide, GridOverlay::Scope::Drawn);
  EXPECT_EQ(grid.cubes_drawn(), 2u);
}

// Focus first draws a full-detail copy of the selection beside the input, in the same renderer
// (ViewerSession::focus_first_renderer). The overlay shows the voxels of the file the user opened: the copy's
// voxels (a cube on its own grid, whose origin is the selected streamline's corner) add no outline, in either
// scope, and the picture is the one without the copy.
TEST_F(WindowGridOverlay, OutlinesTheInputsVoxelsNotThoseOfTheFocusCopy) {
  Tractogram t;
  const float first[] = {1, 1, 0, 9, 5, 0}, selected[] = {4, 4, 0, 9, 8, 0};
  t.add_streamline(first, 2);
  t.add_streamline(selected, 2);
  t.source.path = "two_in_one_voxel";
  VxlFile f = test::make_scene(dir, std::move(t), 10.0);
  const app::FocusCopy copy(std::vector<const VxlFile*>{&f}, {{1}});
  ASSERT_EQ(copy.files().size(), 1u);
  Renderer input(f);
  Renderer focus_first({&f, copy.files()[0]}, 0, 0, nullptr, true, {0, 0});
  GridOverlay grid(input);
  for (const GridOverlay::Scope scope : {GridOverlay::Scope::Drawn, GridOverlay::Scope::All}) {
    const Image expected = overlay_image(input, grid, above_first_voxel(0.0), scope);
    const std::uint64_t cubes = grid.cubes_drawn();
    EXPECT_EQ(cubes, 1u);
    const Image with_copy = overlay_image(focus_first, grid, above_first_voxel(0.0), scope);
    EXPECT_EQ(grid.cubes_drawn(), cubes) << "scope " << int(scope);
    EXPECT_EQ(compare_images(with_copy, expected).differing_pixels, 0u) << "scope " << int(scope);
  }
  // The copy is in the renderer's plan and on another grid: an overlay of every file it draws outlines it.
  GridOverlay every(focus_first);
  const Image both = overlay_image(focus_first, every, above_first_voxel(0.0), GridOverlay::Scope::Drawn);
  EXPECT_EQ(every.cubes_drawn(), 2u);
  EXPECT_GT(test::lit_pixels(both),
            test::lit_pixels(overlay_image(input, grid, above_first_voxel(0.0), GridOverlay::Scope::Drawn)));
}

// A scripted drag (--drag-region): the active sphere moves every frame, the frames are moving ones, the
// selections run off the window's thread and --stats reports their times; the last selection, waited for
// at the end, is where the sphere came to rest.
TEST_F(Window, AScriptedDragReportsTheSelectionsTimes) {
  VXL_REQUIRE_XVFB();
  make_inputs();
  const nlohmann::json j =
      window_stats("--size 200x150 --include -40,-18,10,10 --drag-region 4,0,0 --frames 12 --context-opacity 0.1");
  ASSERT_FALSE(j.is_null());
  EXPECT_GE(j.at("moving_frames").get<int>(), 8);
  EXPECT_GE(j.at("selections").get<int>(), 2);  // the first (at start) and at least one while dragging
  EXPECT_GT(j.at("selection_median_ms").get<double>(), 0.0);
  EXPECT_GE(j.at("selection_p95_ms").get<double>(), j.at("selection_median_ms").get<double>());
  ASSERT_EQ(j.at("selection_ms").size(), j.at("selections").get<std::size_t>());  // each one's time, listed
  for (const auto& ms : j.at("selection_ms")) EXPECT_GT(ms.get<double>(), 0.0);
  // The same figures of the selections after the first (the ones the drag's moves asked for).
  std::vector<double> later;
  for (std::size_t k = 1; k < j.at("selection_ms").size(); ++k) later.push_back(j.at("selection_ms")[k].get<double>());
  EXPECT_EQ(j.at("later_selection_p95_ms").get<double>(), *std::max_element(later.begin(), later.end()))
      << "fewer than 20 selections: the p95 is the slowest";
  EXPECT_GE(j.at("later_selection_p95_ms").get<double>(), j.at("later_selection_median_ms").get<double>());
  // The first picture does not wait for the command line's selection (its --context-opacity is accepted before the
  // selection's groups exist): each frame says whether its picture shows one; once in, it stays, to the last frame.
  // The frames that took a new selection in are marked: the first to show one is, and none without one is.
  // Nothing is refined while a selection is on its way (the picture it changes would be drawn again): no refinement
  // piece comes before a frame that takes a new selection in.
  bool shown = false, refined = false;
  int taken = 0;
  for (const nlohmann::json& f : j.at("frames")) {
    const bool selection = f.value("selection", false), new_selection = f.value("new_selection", false);
    EXPECT_TRUE(selection || !shown) << f.dump();
    EXPECT_TRUE(!new_selection || selection) << f.dump();
    if (selection && !shown) {
      EXPECT_TRUE(new_selection) << f.dump();
    }
    EXPECT_FALSE(new_selection && refined) << "a refinement piece was drawn while this selection was on its way";
    refined |= f.value("work", std::string("whole")) != "whole";
    taken += new_selection;
    shown = selection;
  }
  EXPECT_TRUE(shown);
  EXPECT_GE(taken, 1);
  const test::CommandResult bad = run_voxview_in_xvfb(shell_quoted(vxl) + " --drag-region 1,0 --frames 2");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  const test::CommandResult none = run_voxview_in_xvfb(shell_quoted(vxl) + " --drag-region 1,0,0 --frames 2");
  EXPECT_EQ(none.exit_code, 2) << none.output;
  EXPECT_NE(none.output.find("--drag-region needs a region"), std::string::npos) << none.output;
}

// The window draws a command-line selection as the headless path does (focus and context, the context hidden
// here): the same picture but for rasteriser details.
TEST_F(Window, ASelectionLooksAsItDoesHeadless) {
  VXL_REQUIRE_XVFB();
  make_inputs();
  const std::string args = " --size 320x240 --include 0,-18,10,15 --context-opacity 0 --focus-opacity 0.8";
  const std::string shot = dir.file("shot.png"), headless = dir.file("headless.png");
  CommandResult w = run_voxview_in_xvfb(shell_quoted(vxl) + args + " --frames 5 --screenshot " + shell_quoted(shot));
  ASSERT_EQ(w.exit_code, 0) << w.output;
  // The window shows the region's shell unless B hides it: headless draws it with --show-regions.
  CommandResult h = run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) + args + " --show-regions --render " +
                              shell_quoted(headless));
  ASSERT_EQ(h.exit_code, 0) << h.output;
  const Image a = read_image(shot), b = read_image(headless);
  ImageDiff d = compare_images(a, b);
  EXPECT_LT(d.mean_error, 6e-5) << "differing pixels " << d.differing_pixels;
  // And the selection (without its shell) shows less than the whole tractogram does.
  CommandResult plain = run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) + args + " --render " +
                                  shell_quoted(dir.file("plain.png")));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const Image selected = read_image(dir.file("plain.png"));
  CommandResult all = run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) +
                                " --size 320x240 --opacity 0.8 --render " + shell_quoted(dir.file("all.png")));
  ASSERT_EQ(all.exit_code, 0) << all.output;
  EXPECT_LT(lit_pixels(selected), lit_pixels(read_image(dir.file("all.png"))) * 9 / 10);
  EXPECT_GT(lit_pixels(selected), 50);
}

// The orientation letters, the triad and a background colour are drawn in the window as in --render.
TEST_F(Window, OrientationLabelsAndABackgroundLookAsTheyDoHeadless) {
  VXL_REQUIRE_XVFB();
  make_inputs();
  const std::string args = " --size 320x240 --background '#203040'";
  const std::string shot = dir.file("shot.png"), headless = dir.file("headless.png"), bare = dir.file("bare.png");
  CommandResult w = run_voxview_in_xvfb(shell_quoted(vxl) + args + " --orientation-labels --frames 5 --screenshot " +
                                        shell_quoted(shot));
  ASSERT_EQ(w.exit_code, 0) << w.output;
  CommandResult h = run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) + args +
                              " --orientation-labels --render " + shell_quoted(headless));
  ASSERT_EQ(h.exit_code, 0) << h.output;
  CommandResult b =
      run_shell(shell_quoted(VOXVIEW_CLI) + " " + shell_quoted(vxl) + args + " --render " + shell_quoted(bare));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const Image a = read_image(shot);
  const ImageDiff same = compare_images(a, read_image(headless));
  EXPECT_LT(same.mean_error, 6e-5) << "differing pixels " << same.differing_pixels;
  // Without the labels the picture differs by far more than the window and headless paths do.
  EXPECT_GT(compare_images(a, read_image(bare)).mean_error, 10 * std::max(same.mean_error, 1e-5));
  EXPECT_EQ(a.pixel(0, 0)[0], 0x20);
  EXPECT_EQ(a.pixel(0, 0)[2], 0x40);
}

}  // namespace
}  // namespace vxl
