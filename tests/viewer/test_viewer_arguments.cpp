// voxview's command line: the parser's schema (voxview_cli.h) and how the options combine with a saved view
// and are checked (viewer_arguments.h), without running the program.
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <sys/stat.h>

#include "converter/readers/source_formats.h"
#include "format/base/error.h"
#include "tests/test_support.h"
#include "viewer/app/camera_file.h"
#include "viewer/app/key_bindings.h"
#include "viewer/app/turntable.h"
#include "viewer/app/viewer_arguments.h"
#include "viewer/app/voxview_cli.h"
#include "viewer/platform/image_io.h"
#include "viewer/render/render_settings.h"

namespace vxl {
namespace {

using app::resolve_viewer_options;
using app::ViewerArguments;
using test::ScratchDir;

// The usage error resolve_viewer_options throws, or "no error".
std::string usage_error_of(const ViewerArguments& a) {
  try {
    resolve_viewer_options(a);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage) << e.what();
    return e.reason();
  }
  return "no error";
}

// A saved view unlike the defaults in every setting the command line can give.
app::SavedView saved_view() {
  app::SavedView v;
  v.camera.azimuth_deg = 12;
  v.camera.elevation_deg = -7;
  v.camera.distance = 321;
  v.settings.mode = RenderMode::Exact;
  v.settings.opacity = 0.7f;
  v.settings.color = ColorMode::Fixed;
  v.settings.colormap = Colormap::Hot;
  v.settings.background_color = glm::vec3(1.0f);
  v.settings.orientation_labels = true;
  v.settings.line_width = 3;
  v.settings.clipping.planes = {*parse_axis_clip("y,5")};
  v.size = std::array<int, 2>{640, 480};
  return v;
}

TEST(ViewerArguments, WithoutASavedViewTheCommandLineValuesApply) {
  ViewerArguments a;
  a.options.inputs = {"a.vxl"};
  a.mode = "wboit";  // a value with no "given" mark still applies: there is nothing to override
  a.opacity = 0.25f;
  a.background = "white";
  const app::ViewerOptions o = resolve_viewer_options(a);
  EXPECT_EQ(o.settings.mode, RenderMode::Wboit);
  EXPECT_EQ(o.settings.opacity, 0.25f);
  EXPECT_EQ(o.settings.background_color, glm::vec3(1.0f));
  EXPECT_EQ(o.settings.color, ColorMode::Direction);
  EXPECT_EQ(o.settings.colormap, Colormap::Viridis);
  EXPECT_EQ(o.width, 1024);
  EXPECT_EQ(o.height, 1024);
  EXPECT_FALSE(o.camera);
  EXPECT_EQ(o.inputs, std::vector<std::string>{"a.vxl"});
}

TEST(ViewerArguments, ASavedViewOverridesTheDefaultsAndGivenOptionsOverrideIt) {
  ScratchDir dir;
  const std::string path = dir.file("view.json");
  app::write_view(path, saved_view());

  ViewerArguments a;
  a.camera_file = path;
  {
    const app::ViewerOptions o = resolve_viewer_options(a);
    ASSERT_TRUE(o.camera);
    EXPECT_EQ(o.camera->azimuth_deg, 12);
    EXPECT_EQ(o.camera->distance, 321);
    EXPECT_EQ(o.settings.mode, RenderMode::Exact);
    EXPECT_EQ(o.settings.opacity, 0.7f);
    EXPECT_EQ(o.settings.color, ColorMode::Fixed);
    EXPECT_EQ(o.settings.colormap, Colormap::Hot);
    EXPECT_EQ(o.settings.background_color, glm::vec3(1.0f));
    EXPECT_TRUE(o.settings.orientation_labels);
    EXPECT_EQ(o.settings.line_width, 3);
    ASSERT_EQ(o.settings.clipping.planes.size(), 1u);
    EXPECT_EQ(o.settings.clipping.planes[0].axis, 1);
    EXPECT_EQ(o.width, 640);
    EXPECT_EQ(o.height, 480);
  }

  a.mode = "basic";
  a.opacity = 0.5f;
  a.size = "100x50";
  a.clips = {"-z,2"};
  a.given = {"--mode", "--size", "--clip"};  // --opacity not given: the saved 0.7 stays
  const app::ViewerOptions o = resolve_viewer_options(a);
  EXPECT_EQ(o.settings.mode, RenderMode::Basic);
  EXPECT_EQ(o.settings.opacity, 0.7f);
  EXPECT_EQ(o.settings.background_color, glm::vec3(1.0f));
  EXPECT_EQ(o.width, 100);
  EXPECT_EQ(o.height, 50);
  ASSERT_EQ(o.settings.clipping.planes.size(), 1u);  // given planes replace the saved ones
  EXPECT_EQ(o.settings.clipping.planes[0].axis, 2);
  EXPECT_FALSE(o.settings.clipping.planes[0].keep_above);
}

TEST(ViewerArguments, ASavedViewWithoutAnOpacityKeepsTheCommandLines) {
  ScratchDir dir;
  const std::string path = dir.file("partial.json");
  std::ofstream(path) << R"({"voxview_view": 1, "settings": {"mode": "unsorted"}})";
  ViewerArguments a;
  a.camera_file = path;
  a.opacity = 0.45f;
  const app::ViewerOptions o = resolve_viewer_options(a);
  EXPECT_EQ(o.settings.mode, RenderMode::Unsorted);
  EXPECT_EQ(o.settings.opacity, 0.45f);
  EXPECT_EQ(o.width, 1024);
}

TEST(ViewerArguments, ValuesParse) {
  ViewerArguments a;
  a.options.image = "t1.nii";
  a.range = "0,0.5";
  a.image_range = "10,800";
  a.slices = "view,axial";
  a.focus = "-5,0,12.5";
  a.fixed_color = "#ff8000";
  a.groups = {"CST=#00ff00:0.5", "AF=:0"};
  a.view = "-35,25";
  a.slab = 12;
  a.given = {"--range", "--image-range", "--slices", "--focus", "--fixed-color", "--slab"};
  const app::ViewerOptions o = resolve_viewer_options(a);
  const RenderSettings& s = o.settings;
  ASSERT_TRUE(s.range);
  EXPECT_EQ(*s.range, (std::array<float, 2>{0.0f, 0.5f}));
  ASSERT_TRUE(s.slices.range);
  EXPECT_EQ(*s.slices.range, (std::array<float, 2>{10.0f, 800.0f}));
  EXPECT_TRUE(s.slices.view_plane);
  EXPECT_TRUE(s.slices.axial);
  EXPECT_FALSE(s.slices.coronal);
  EXPECT_FALSE(s.slices.sagittal);
  ASSERT_TRUE(o.focus);
  EXPECT_EQ(*o.focus, glm::dvec3(-5, 0, 12.5));
  EXPECT_EQ(hex_color(s.fixed_color), "#ff8000");
  ASSERT_EQ(s.group_styles.size(), 2u);
  EXPECT_EQ(s.group_styles[0].name, "CST");
  EXPECT_EQ(s.group_styles[0].opacity, 0.5f);
  EXPECT_EQ(s.group_styles[1].name, "AF");
  EXPECT_FALSE(s.group_styles[1].color);
  EXPECT_EQ(s.group_styles[1].opacity, 0.0f);
  ASSERT_TRUE(o.view);
  EXPECT_EQ(*o.view, (std::array<double, 2>{-35, 25}));
  EXPECT_EQ(s.clipping.slab_mm, 12);

  a.slices = "none";
  EXPECT_FALSE(resolve_viewer_options(a).settings.slices.any());
}

// One option given with `value`: its field set and the option marked given.
ViewerArguments given(const char* option, std::string ViewerArguments::*field, const std::string& value) {
  ViewerArguments a;
  a.options.image = "t1.nii";
  a.*field = value;
  a.given = {option};
  return a;
}

TEST(ViewerArguments, BadOrConflictingOptionsAreUsageErrors) {
  auto error_contains = [](const ViewerArguments& a, const std::string& part) {
    const std::string error = usage_error_of(a);
    EXPECT_NE(error.find(part), std::string::npos) << error;
  };
  error_contains(given("--range", &ViewerArguments::range, "1,0"), "--range: expected MIN,MAX");
  error_contains(given("--image-range", &ViewerArguments::image_range, "5"), "--image-range: expected MIN,MAX");
  error_contains(given("--slices", &ViewerArguments::slices, "axial,top"), "--slices: expected");
  error_contains(given("--focus", &ViewerArguments::focus, "1,2"), "--focus: expected X,Y,Z");
  error_contains(given("--view", &ViewerArguments::view, "sideways"), "unknown view 'sideways'");
  error_contains(given("--size", &ViewerArguments::size, "0x5"), "--size must be WxH");
  error_contains(given("--size", &ViewerArguments::size, "16385x5"), "--size must be WxH");
  error_contains(given("--mode", &ViewerArguments::mode, "fancy"), "--mode: unknown mode 'fancy'");
  error_contains(given("--color", &ViewerArguments::color, "rainbow"), "--color: unknown colour mode");
  error_contains(given("--colormap", &ViewerArguments::colormap, "jet"), "--colormap: unknown colour map");
  error_contains(given("--fixed-color", &ViewerArguments::fixed_color, "red"), "--fixed-color: expected #RRGGBB");
  error_contains(given("--background", &ViewerArguments::background, "purple"),
                 "--background: expected a name (black, white, grey, darkgrey, lightgrey), #RRGGBB");
  ViewerArguments colorbar;
  colorbar.colorbar = true;
  error_contains(colorbar, "--colorbar goes with --color scalar");
  colorbar.color = "scalar";
  EXPECT_EQ(usage_error_of(colorbar), "no error");

  ViewerArguments a = given("--size", &ViewerArguments::size, "800x600");
  EXPECT_EQ(usage_error_of(a), "no error");
  a.clips = {"x,1", "y,1", "z,1", "x,2"};
  error_contains(a, "--clip: at most 3 clip planes (got 4)");
  a.clips = {"w,1"};
  error_contains(a, "--clip: expected AXIS,POS");
  a.clips.clear();
  a.groups = {"CST="};
  error_contains(a, "--group: expected");
  a.groups.clear();
  a.options.turntable = 36;
  error_contains(a, "--turntable needs --render");
  a.options.render_png = "x.png";
  EXPECT_EQ(usage_error_of(a), "no error");

  ViewerArguments no_image = given("--slices", &ViewerArguments::slices, "axial");
  no_image.options.image.reset();
  error_contains(no_image, "--image-range and --slices need --image");
}

// Options that draw nothing (an azimuth of 1e308, a slab of 1e-300 mm, a focus at 1e308 mm) or make no
// sense (a frame budget of NaN, an infinite orbit) are usage errors.
TEST(ViewerArguments, OptionsThatDrawNothingAreUsageErrors) {
  auto error_contains = [](const ViewerArguments& a, const std::string& part) {
    const std::string error = usage_error_of(a);
    EXPECT_NE(error.find(part), std::string::npos) << error;
  };
  ViewerArguments view = given("--view", &ViewerArguments::view, "1e308,1e308");
  error_contains(view, "--view: unknown view '1e308,1e308'");
  ViewerArguments slab;
  slab.slab = 1e-300;
  slab.given.insert("--slab");
  error_contains(slab, "--slab: expected a thickness in [0.001, 1e+07] mm");
  error_contains(given("--focus", &ViewerArguments::focus, "1e308,0,0"), "--focus: expected X,Y,Z");
  ViewerArguments budget;
  budget.options.frame_budget_ms = std::numeric_limits<double>::quiet_NaN();
  error_contains(budget, "--frame-budget: expected milliseconds");
  ViewerArguments orbit;
  orbit.options.orbit_deg = std::numeric_limits<double>::infinity();
  error_contains(orbit, "--orbit: expected degrees");
  EXPECT_EQ(usage_error_of(given("--view", &ViewerArguments::view, "-720,95")), "no error");  // elevation clamped
}

// A view file without "camera" is framed as without a view file, not shown from the default camera (target
// at the origin, 300 mm away: a picture of whatever lies there); its settings still apply.
TEST(ViewerArguments, AViewFileWithoutACameraIsFramedAsWithoutOne) {
  ScratchDir dir;
  const std::string path = dir.file("look.json");
  std::ofstream(path) << R"({"voxview_view": 1, "settings": {"lighting": true, "mode": "exact"}})";
  ViewerArguments a;
  a.camera_file = path;
  const app::ViewerOptions o = resolve_viewer_options(a);
  EXPECT_FALSE(o.camera);
  EXPECT_TRUE(o.settings.lighting);
  EXPECT_EQ(o.settings.mode, RenderMode::Exact);
}

// Every output is checked before anything is read or drawn: --render into a missing folder or onto a
// folder fails before the rendering, not with exit 70 after it; a FIFO or a device is never replaced by a
// regular file.
TEST(ViewerArguments, OutputPathsAreCheckedFirstAndNeverReplaceAFifoOrDevice) {
  ScratchDir dir;
  const std::string fifo = dir.file("fifo.png"), null_link = dir.file("null.png");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::filesystem::create_symlink("/dev/null", null_link);
  auto output_error_of = [](const ViewerArguments& a) -> std::string {
    try {
      resolve_viewer_options(a);
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Output) << e.what();
      return e.what();
    }
    return "no error";
  };
  auto rendering_to = [](const std::string& png) {
    ViewerArguments a;
    a.options.inputs = {"a.vxl"};
    a.options.render_png = png;
    return a;
  };
  EXPECT_NE(output_error_of(rendering_to(dir.file("missing/x.png"))).find("cannot write into the folder"),
            std::string::npos);
  EXPECT_NE(output_error_of(rendering_to(dir.file(""))).find("is a directory"), std::string::npos);
  EXPECT_NE(output_error_of(rendering_to(fifo)).find("is a FIFO"), std::string::npos);
  EXPECT_NE(output_error_of(rendering_to(null_link)).find("is a character device"), std::string::npos);
  EXPECT_EQ(output_error_of(rendering_to(dir.file("new.png"))), "no error");

  // The second of three turntable frames.
  ViewerArguments turn = rendering_to(dir.file("t.png"));
  turn.options.turntable = 3;
  ASSERT_EQ(::mkfifo(app::turntable_frame_path(dir.file("t.png"), 1, 3).c_str(), 0600), 0);
  EXPECT_NE(output_error_of(turn).find("t_001.png: is a FIFO"), std::string::npos) << output_error_of(turn);

  for (auto field :
       {&app::ViewerOptions::save_camera, &app::ViewerOptions::stats_json, &app::ViewerOptions::screenshot}) {
    ViewerArguments a;
    a.options.inputs = {"a.vxl"};
    a.options.*field = fifo;
    EXPECT_NE(output_error_of(a).find("is a FIFO"), std::string::npos);
  }
  struct stat st {};
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  ASSERT_EQ(::lstat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));

  // The program: exit 5, before the input is even opened.
  for (const std::string& out : {dir.file("missing/x.png"), dir.file(""), fifo}) {
    const auto r = test::run_program(VOXVIEW_CLI, test::q(dir.file("absent.vxl")) + " --render " + test::q(out));
    EXPECT_EQ(r.exit_code, 5) << r.output;
  }
}

// A size the GL driver cannot allocate, from --size or from a view file, is exit 4 naming what fits (not
// exit 70, "framebuffer incomplete"); a driver that allocates it draws it.
TEST(Voxview, SizeBeyondWhatTheDriverAllocatesIsUnsupported) {
  ScratchDir dir;
  const std::string tck = dir.file("s.tck"), vxl = dir.file("s.vxl"), view = dir.file("big.json");
  ASSERT_EQ(test::run_cli("synth " + test::q(tck) + " --streamlines 20").exit_code, 0);
  ASSERT_EQ(test::run_cli("convert " + test::q(tck) + " " + test::q(vxl)).exit_code, 0);
  std::ofstream(view) << R"({"voxview_view": 1, "size": [16384, 8192]})";
  for (const std::string& size : {std::string("--size 16384x8192"), "--camera " + test::q(view)}) {
    SCOPED_TRACE(size);
    const auto r =
        test::run_program(VOXVIEW_CLI, test::q(vxl) + " --render " + test::q(dir.file("o.png")) + " " + size);
    if (r.exit_code == 0) continue;
    EXPECT_EQ(r.exit_code, 4) << r.output;
    EXPECT_NE(r.output.find("image size 16384x8192: the GL driver cannot allocate"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("o.png")));
  }
}

// A view file whose scalar, groups or colouring the scene cannot honour is a bad file (exit 3, naming it);
// the same from the command line is a usage error (exit 2).
TEST(Voxview, ColourSettingsFromAViewFileAreTheFilesErrors) {
  ScratchDir dir;
  const std::string tck = dir.file("s.tck"), vxl = dir.file("s.vxl"), png = dir.file("o.png");
  ASSERT_EQ(test::run_cli("synth " + test::q(tck) + " --streamlines 20").exit_code, 0);
  ASSERT_EQ(test::run_cli("convert " + test::q(tck) + " " + test::q(vxl)).exit_code, 0);
  const std::vector<std::pair<std::string, std::string>> settings = {
      {R"("scalar": "fa")", "settings.scalar: no value set 'fa'"},
      {R"("groups": [{"name": "CST", "opacity": 0.5}])", "settings.groups: no group 'CST'"},
      {R"("color": "scalar")", "settings.color: no per-point or per-streamline values"}};
  for (const auto& [setting, message] : settings) {
    SCOPED_TRACE(setting);
    const std::string view = dir.file("v.json");
    std::ofstream(view) << R"({"voxview_view": 1, "settings": {)" + setting + "}}";
    const auto r = test::run_program(
        VOXVIEW_CLI, test::q(vxl) + " --camera " + test::q(view) + " --render " + test::q(png) + " --size 32x32");
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find("v.json: " + message), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("in " + vxl), std::string::npos) << r.output;
  }
  for (const std::string option : {"--scalar fa", "--group CST=:0.5", "--color scalar"}) {
    const auto r = test::run_program(VOXVIEW_CLI, test::q(vxl) + " " + option + " --render " + test::q(png));
    EXPECT_EQ(r.exit_code, 2) << option << ": " << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(png));
}

// The schema: which options were given, values that start with '-', the lists the help takes from their tables.
TEST(VoxviewCli, ParsesNegativeValuesAndNotesGivenOptions) {
  ViewerArguments a;
  CLI::App cli{app::voxview_description("test")};
  app::declare_voxview_options(cli, a);
  const char* argv[] = {"voxview", "a.vxl", "b.tck", "--clip", "-x,10", "--focus", "-5,0,0", "--mode", "exact"};
  app::parse_voxview_command_line(cli, a, static_cast<int>(std::size(argv)), argv);
  EXPECT_EQ(a.options.inputs, (std::vector<std::string>{"a.vxl", "b.tck"}));
  EXPECT_EQ(a.clips, std::vector<std::string>{"-x,10"});
  EXPECT_EQ(a.focus, "-5,0,0");
  EXPECT_EQ(a.mode, "exact");
  EXPECT_EQ(a.opacity, 0.3f);
  EXPECT_TRUE(a.was_given("--mode"));
  EXPECT_TRUE(a.was_given("--clip"));
  EXPECT_TRUE(a.was_given("--focus"));
  EXPECT_FALSE(a.was_given("--opacity"));
  EXPECT_FALSE(a.was_given("--size"));
}

TEST(VoxviewCli, LevelAndGpuMemoryParse) {
  ViewerArguments a;
  CLI::App cli{app::voxview_description("test")};
  app::declare_voxview_options(cli, a);
  const char* argv[] = {"voxview", "a.vxl", "--gpu-memory", "2G", "--level", "2"};
  app::parse_voxview_command_line(cli, a, static_cast<int>(std::size(argv)), argv);
  const app::ViewerOptions o = resolve_viewer_options(a);
  EXPECT_EQ(o.gpu_memory, std::optional<std::uint64_t>(2ull << 30));
  EXPECT_EQ(o.level, std::optional<std::uint32_t>(2));
  ViewerArguments none;
  EXPECT_FALSE(resolve_viewer_options(none).gpu_memory.has_value());
  EXPECT_FALSE(resolve_viewer_options(none).level.has_value());
  ViewerArguments bad;
  bad.gpu_memory = "lots";
  EXPECT_NE(usage_error_of(bad).find("--gpu-memory 'lots' is not a memory size"), std::string::npos);
  bad.gpu_memory = "0";
  EXPECT_NE(usage_error_of(bad).find("--gpu-memory '0' is not a memory size"), std::string::npos);
  ViewerArguments deep;
  CLI::App cli2{app::voxview_description("test")};
  app::declare_voxview_options(cli2, deep);
  const char* too_deep[] = {"voxview", "a.vxl", "--level", "8"};
  EXPECT_THROW(app::parse_voxview_command_line(cli2, deep, static_cast<int>(std::size(too_deep)), too_deep),
               CLI::ValidationError);
}

TEST(VoxviewCli, ModesAndKeysComeFromTheirTables) {
  ViewerArguments a;
  CLI::App cli{app::voxview_description("test")};
  app::declare_voxview_options(cli, a);
  const std::string help = cli.help();
  std::string modes;  // every mode of render_settings.cpp's table, in its order
  for (const RenderModeInfo& m : render_modes()) modes += (modes.empty() ? "" : " | ") + std::string(m.name);
  ASSERT_GE(render_modes().size(), 8u);
  EXPECT_NE(help.find(modes), std::string::npos) << help;
  for (const app::KeyBinding& b : app::key_bindings())
    EXPECT_NE(help.find(std::string(b.keys) + ": " + b.description), std::string::npos) << b.keys;

  const char* argv[] = {"voxview", "a.vxl", "--mode", "fancy"};
  EXPECT_THROW(app::parse_voxview_command_line(cli, a, 4, argv), CLI::ValidationError);
}

// The text of `help` from `from` up to `to` (the next option's name), empty when `from` is missing.
std::string help_part(const std::string& help, const std::string& from, const std::string& to) {
  const std::size_t start = help.find(from);
  if (start == std::string::npos) return {};
  return help.substr(start, help.find(to, start + from.size()) - start);
}

TEST(VoxviewCli, SourceSuffixesAndStreamedFormatsComeFromTheReaderTable) {
  ViewerArguments a;
  CLI::App cli{app::voxview_description("test")};
  app::declare_voxview_options(cli, a);
  const std::string help = cli.help();
  const std::string description = help_part(help, "voxview test", "Opening a .vxl");
  const std::string files = help_part(help, "files", "--render");
  const std::string memory_limit = help_part(help, "  --memory-limit SIZE", "  --gpu-memory");
  ASSERT_FALSE(memory_limit.empty()) << help;
  for (const SourceFormat& f : source_formats()) {
    for (const char* suffix : f.suffixes) {
      EXPECT_NE(description.find(suffix), std::string::npos) << suffix << " in " << description;
      EXPECT_NE(files.find(suffix), std::string::npos) << suffix << " in " << files;
    }
    // Each format is named as streamed, or as refused under --memory-limit.
    EXPECT_NE(memory_limit.find(f.name), std::string::npos) << f.name << " in " << memory_limit;
  }
}

// Whether voxview's command line takes `args` (after "voxview a.vxl").
bool accepts(const std::vector<std::string>& args) {
  ViewerArguments a;
  CLI::App cli{app::voxview_description("test")};
  app::declare_voxview_options(cli, a);
  std::vector<const char*> argv = {"voxview", "a.vxl"};
  for (const std::string& arg : args) argv.push_back(arg.c_str());
  try {
    app::parse_voxview_command_line(cli, a, static_cast<int>(argv.size()), argv.data());
    return true;
  } catch (const CLI::ParseError&) {
    return false;
  }
}

TEST(VoxviewCli, OptionValueListsComeFromTheirTables) {
  ASSERT_EQ(color_mode_names().size(), 4u);
  for (const std::string& name : color_mode_names()) {
    EXPECT_TRUE(accepts({"--color", name})) << name;
    EXPECT_TRUE(parse_color_mode(name)) << name;
  }
  EXPECT_FALSE(accepts({"--color", "rainbow"}));
  ASSERT_EQ(colormap_names().size(), 3u);
  for (const std::string& name : colormap_names()) EXPECT_TRUE(accepts({"--colormap", name})) << name;
  EXPECT_TRUE(accepts({"--colormap", "gray"}));
  EXPECT_FALSE(accepts({"--colormap", "jet"}));

  // Every extension the formats' text names is one picture_format_of knows, and the help gives that text.
  const std::string formats = picture_formats_text();
  int extensions = 0;
  for (std::size_t at = formats.find('.'); at != std::string::npos; at = formats.find('.', at + 1)) {
    const std::string extension = formats.substr(at, formats.find_first_of(",)", at) - at);
    EXPECT_FALSE(picture_format_of("a" + extension).empty()) << extension;
    ++extensions;
  }
  EXPECT_EQ(extensions, 6) << formats;
  EXPECT_TRUE(picture_format_of("a.bmp").empty());
  ViewerArguments a;
  CLI::App cli{app::voxview_description("test")};
  app::declare_voxview_options(cli, a);
  const std::string help = cli.help();
  EXPECT_NE(help_part(help, "  --render", "  --turntable").find(formats), std::string::npos) << help;
  EXPECT_NE(help_part(help, "  --screenshot", "\n\n").find(formats), std::string::npos) << help;

  // Every name the views' text lists, other names in brackets too, is a view --view takes.
  const std::string views = view_names_text();
  EXPECT_NE(help_part(help, "  --view", "  --size").find(views), std::string::npos) << help;
  int named = 0;
  for (std::size_t at = 0; at < views.size();) {
    const std::size_t end = views.find_first_of(",()", at);
    std::string name = views.substr(at, end == std::string::npos ? std::string::npos : end - at);
    while (!name.empty() && name.back() == ' ') name.pop_back();
    if (!name.empty()) {
      EXPECT_TRUE(parse_view(name)) << "'" << name << "' in " << views;
      ++named;
    }
    at = end == std::string::npos ? views.size() : views.find_first_not_of(",() ", end);
  }
  EXPECT_EQ(named, 9) << views;
  EXPECT_FALSE(parse_view("axil"));
}

}  // namespace
}  // namespace vxl
