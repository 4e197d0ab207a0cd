// voxview's command line: a mistyped option gets the nearest one, an unknown view the list of views, and
// messages about options carry no file name; a picture is written in the format its extension names, through
// the picture module loaded when it is written (a missing module is an error naming it, and writes nothing); the
// window's options are refused with --render, and --render's --stats says where the time went.
#include <sys/resource.h>

#include <filesystem>

#include <epoxy/gl.h>
#include <nlohmann/json.hpp>

#include "tests/hostile_vxl.h"
#include "tests/test_support.h"
#include "viewer/platform/egl_context.h"
#include "viewer/platform/image_io.h"
#include "viewer/render/gpu_scene.h"
#include "viewer/render/scene_layout.h"

namespace vxl {
namespace {

// A 20-streamline source, a.tck, in `dir`, and the arguments that draw it headless at 16x16 into a.png there.
std::string small_source_rendered(const test::ScratchDir& dir) {
  EXPECT_EQ(test::run_cli("synth " + test::q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  return test::q(dir.file("a.tck")) + " --size 16x16 --render " + test::q(dir.file("a.png"));
}

TEST(VoxviewCommandLine, TyposAndUnknownViewsSayWhatIsKnown) {
  const test::CommandResult typo = test::run_program(VOXVIEW_CLI, "x.vxl --render x.png --opacty 0.5");
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.output.find("unknown option --opacty; did you mean --opacity?"), std::string::npos) << typo.output;
  test::ScratchDir dir;
  ASSERT_EQ(test::run_cli("synth " + test::q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  const test::CommandResult view = test::run_program(
      VOXVIEW_CLI, test::q(dir.file("a.tck")) + " --render " + test::q(dir.file("a.png")) + " --view axil");
  EXPECT_EQ(view.exit_code, 2);
  EXPECT_NE(view.output.find("unknown view 'axil' (expected axial (superior), inferior,"), std::string::npos)
      << view.output;
  EXPECT_EQ(view.output.find("<input>"), std::string::npos) << view.output;
}

// An opacity or a line width must be a number in its range: NaN (which every range check lets through by
// comparing false) and infinities are usage errors, naming the option, before anything is drawn.
TEST(VoxviewCommandLine, OpacitiesAndLineWidthsThatAreNoNumberInTheirRangeAreUsageErrors) {
  test::ScratchDir dir;
  const std::string render = small_source_rendered(dir);
  const char* const refused[][2] = {
      {"--opacity", "nan"},       {"--opacity", "-nan"},        {"--opacity", "inf"},
      {"--opacity", "2"},         {"--line-width", "nan"},      {"--line-width", "inf"},
      {"--focus-opacity", "nan"}, {"--context-opacity", "nan"}, {"--context-opacity", "-0.5"}};
  for (const auto& [option, value] : refused) {
    const test::CommandResult r =
        test::run_program(VOXVIEW_CLI, render + " --include 0,0,0,50 " + option + " " + value);
    EXPECT_EQ(r.exit_code, 2) << option << " " << value << ": " << r.output;
    EXPECT_NE(r.output.find(std::string(option) + ": expected a number from"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("a.png"))) << option << " " << value;
  }
  EXPECT_EQ(test::run_program(VOXVIEW_CLI, render + " --opacity 1e-3 --line-width 16").exit_code, 0);
}

// A picture larger than the driver holds (llvmpipe caps one buffer's bytes, below its limit on a side) is
// refused from the driver's answer, before any framebuffer is made: exit 4 saying what does fit, at a small part
// of the memory that allocating and shrinking would take (1.9 GB on the development machine).
TEST(VoxviewCommandLine, APictureTheDriverCannotHoldIsRefusedBeforeAllocating) {
  test::ScratchDir dir;
  ASSERT_EQ(test::run_cli("synth " + test::q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  GLint side = 0;
  {
    HeadlessGlContext context;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &side);
  }
  const std::string size = std::to_string(side) + "x" + std::to_string(side * 3 / 4);
  const test::CommandResult r = test::run_program(
      VOXVIEW_CLI, test::q(dir.file("a.tck")) + " --render " + test::q(dir.file("a.png")) + " --size " + size);
  if (r.exit_code == 0) GTEST_SKIP() << "this driver holds a " << size << " picture";
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("the driver holds no float colour buffer this large"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the largest of this shape it allocates is "), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("a.png")));
  rusage children{};
  getrusage(RUSAGE_CHILDREN, &children);
  EXPECT_LT(children.ru_maxrss, 1 << 20) << "KiB: a framebuffer was allocated";
}

TEST(VoxviewCommandLine, APictureIsWrittenInTheFormatItsExtensionNames) {
  test::ScratchDir dir;
  ASSERT_EQ(test::run_cli("synth " + test::q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  struct Case {
    const char* name;
    std::string magic;  // the format's first bytes
  };
  const Case cases[] = {{"a.png", "\x89PNG"}, {"a.jpg", "\xFF\xD8\xFF"}, {"a.TIFF", "II*"}, {"a.exr", "v/1\x01"}};
  Image png;
  for (const Case& c : cases) {
    const test::CommandResult r = test::run_program(
        VOXVIEW_CLI, test::q(dir.file("a.tck")) + " --size 64x48 --render " + test::q(dir.file(c.name)));
    ASSERT_EQ(r.exit_code, 0) << c.name << ": " << r.output;
    const std::vector<char> bytes = test::slurp(dir.file(c.name));
    ASSERT_GE(bytes.size(), c.magic.size());
    EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + c.magic.size()), c.magic) << c.name;
    // Every format holds the same picture (JPEG within its compression).
    const Image read = read_image(dir.file(c.name));
    EXPECT_EQ(read.width, 64);
    EXPECT_EQ(read.height, 48);
    if (png.width == 0) {
      png = read;
    } else {
      const double tolerance = c.magic[0] == '\xFF' ? 0.03 : 0.003;
      EXPECT_LE(compare_images(png, read).mean_error, tolerance) << c.name;
    }
  }
  // An extension that names no format is a usage error before anything is drawn, and writes nothing.
  const test::CommandResult bmp =
      test::run_program(VOXVIEW_CLI, test::q(dir.file("a.tck")) + " --render " + test::q(dir.file("a.bmp")));
  EXPECT_EQ(bmp.exit_code, 2) << bmp.output;
  EXPECT_NE(bmp.output.find("names no picture format"), std::string::npos) << bmp.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("a.bmp")));
}

// --voxel-size takes what `voxlines convert` takes (auto too), and a size, slab, frame count or budget out of range
// is a usage error saying what is expected, not the largest double in full.
TEST(VoxviewCommandLine, VoxelSizeAutoAndOutOfRangeSizesAsConvertSaysThem) {
  test::ScratchDir dir;
  const std::string render = small_source_rendered(dir);
  const test::CommandResult automatic = test::run_program(VOXVIEW_CLI, render + " --voxel-size auto");
  EXPECT_EQ(automatic.exit_code, 0) << automatic.output;
  EXPECT_NE(automatic.output.find("' --voxel-size auto"), std::string::npos)
      << "the convert hint: " << automatic.output;
  const char* const refused[][3] = {{"--voxel-size", "0", "expected a positive number of mm or auto, got '0'"},
                                    {"--voxel-size", "-1", "expected a positive number of mm or auto, got '-1'"},
                                    {"--slab", "0", "expected a positive number of mm, got '0'"},
                                    {"--frames", "0", "expected a positive number of frames, got '0'"},
                                    {"--frame-budget", "-1", "expected a number of milliseconds >= 0, got '-1'"}};
  for (const auto& [option, value, message] : refused) {
    const std::string window = test::q(dir.file("a.tck")) + " --size 16x16";
    const std::string args = std::string(option).rfind("--frame", 0) == 0 ? window : render;
    const test::CommandResult r = test::run_program(VOXVIEW_CLI, args + " " + option + " " + value);
    EXPECT_EQ(r.exit_code, 2) << option << " " << value << ": " << r.output;
    EXPECT_NE(r.output.find(std::string(option) + ": " + message), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("179769"), std::string::npos) << r.output;
  }
}

// --color scalar without values says how to get them: for a source, --tsf; for a .vxl, whose values were fixed when
// it was converted (voxview refuses --tsf there), converting its source again.
TEST(VoxviewCommandLine, ColourByValueWithoutValuesSaysHowToAddThem) {
  test::ScratchDir dir;
  ASSERT_EQ(test::run_cli("synth " + test::q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  ASSERT_EQ(test::run_cli("convert " + test::q(dir.file("a.tck")) + " " + test::q(dir.file("a.vxl"))).exit_code, 0);
  const std::string options = " --size 16x16 --color scalar --render " + test::q(dir.file("a.png"));
  const test::CommandResult source = test::run_program(VOXVIEW_CLI, test::q(dir.file("a.tck")) + options);
  EXPECT_EQ(source.exit_code, 2) << source.output;
  EXPECT_NE(source.output.find("(add a TSF with --tsf,"), std::string::npos) << source.output;
  const test::CommandResult converted = test::run_program(VOXVIEW_CLI, test::q(dir.file("a.vxl")) + options);
  EXPECT_EQ(converted.exit_code, 2) << converted.output;
  EXPECT_NE(converted.output.find("voxlines convert SOURCE OUT.vxl --tsf FILE.tsf"), std::string::npos)
      << converted.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("a.png")));
}

// A source or a package opens through a temporary .vxl in $TMPDIR: a TMPDIR that names no folder is an output
// error (exit 5) that names the variable, before anything is drawn, not an internal error.
TEST(VoxviewCommandLine, ATmpdirThatNamesNoFolderIsAnOutputErrorNamingIt) {
  test::ScratchDir dir;
  ASSERT_EQ(test::run_cli("synth " + test::q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  const std::string missing = dir.file("no-such-folder");
  const test::CommandResult r =
      test::run_program("TMPDIR=" + test::q(missing) + " " + VOXVIEW_CLI,
                        test::q(dir.file("a.tck")) + " --size 16x16 --render " + test::q(dir.file("a.png")));
  EXPECT_EQ(r.exit_code, 5) << r.output;
  EXPECT_NE(r.output.find("TMPDIR=" + missing + ": names no folder for temporary files"), std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("a.png")));
}

// PNG and JPEG need no module; TIFF and OpenEXR do, and without it are refused (exit 4) naming it.
TEST(VoxviewCommandLine, AMissingPictureModuleIsAnErrorThatNamesItAndWritesNothing) {
  test::ScratchDir dir;
  ASSERT_EQ(test::run_cli("synth " + test::q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  const std::string without = "VOXLINES_PICTURE_MODULE=" + test::q(dir.file("none.so")) + " " + VOXVIEW_CLI;
  const std::string args = test::q(dir.file("a.tck")) + " --size 32x32 --render ";
  for (const char* light : {"a.png", "a.jpg"}) {
    EXPECT_EQ(test::run_program(without, args + test::q(dir.file(light))).exit_code, 0) << light;
    EXPECT_TRUE(std::filesystem::exists(dir.file(light))) << light;
    std::filesystem::remove(dir.file(light));
  }
  const test::CommandResult missing = test::run_program(without, args + test::q(dir.file("a.tif")));
  EXPECT_EQ(missing.exit_code, 4) << missing.output;
  EXPECT_NE(missing.output.find("the picture module libvoxlines_pictures.so (OpenImageIO), which could not be loaded"),
            std::string::npos)
      << missing.output;
  EXPECT_NE(missing.output.find(dir.file("none.so")), std::string::npos) << missing.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("a.tif")));
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename(), "a.tck") << "left behind: " << e.path();
  // Found where the build put it, the same command writes the picture.
  EXPECT_EQ(test::run_program(VOXVIEW_CLI, args + test::q(dir.file("a.tif"))).exit_code, 0);
  EXPECT_TRUE(std::filesystem::exists(dir.file("a.tif")));
}

// The window's options would do nothing with --render, which draws its pictures and quits: each is a usage error
// naming both, before anything is drawn.
TEST(VoxviewCommandLine, TheWindowsOptionsAreRefusedWithRender) {
  test::ScratchDir dir;
  const std::string render = small_source_rendered(dir);
  const std::vector<std::string> options = {"--frames 3",          "--orbit 5",
                                            "--frame-budget 50",   "--no-exact-when-still",
                                            "--drag-region 1,0,0", "--screenshot " + test::q(dir.file("b.png")),
                                            "--until-refined",     "--partial-pictures always"};
  for (const std::string& option : options) {
    const test::CommandResult r = test::run_program(VOXVIEW_CLI, render + " " + option);
    EXPECT_EQ(r.exit_code, 2) << option << ": " << r.output;
    const std::string name = option.substr(0, option.find(' '));
    EXPECT_NE(r.output.find("--render excludes " + name), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("a.png"))) << option;
    EXPECT_FALSE(std::filesystem::exists(dir.file("b.png"))) << option;
  }
}

// A choice the option does not have is a usage error before anything opens, naming the choices.
TEST(VoxviewCommandLine, AnUnknownPartialPicturesChoiceIsRefused) {
  const test::CommandResult r = test::run_program(VOXVIEW_CLI, "missing.vxl --partial-pictures sometimes");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--partial-pictures: sometimes not in {auto,always,never}"), std::string::npos) << r.output;
}

// --voxel-size and --memory-limit shape a conversion: with only .vxl and .vxlz inputs, which are converted already,
// they are usage errors rather than ignored; with a source tractogram among the inputs they apply to it.
TEST(VoxviewCommandLine, ConversionOptionsWithNothingToConvertAreRefused) {
  test::ScratchDir dir;
  const std::string tck = dir.file("a.tck"), vxl = dir.file("a.vxl"), vxlz = dir.file("a.vxlz");
  ASSERT_EQ(test::run_cli("synth " + test::q(tck) + " --streamlines 20").exit_code, 0);
  ASSERT_EQ(test::run_cli("convert " + test::q(tck) + " " + test::q(vxl)).exit_code, 0);
  ASSERT_EQ(test::run_cli("pack " + test::q(vxl) + " " + test::q(vxlz)).exit_code, 0);
  const std::string render = " --size 16x16 --render " + test::q(dir.file("o.png"));
  for (const std::string& inputs : {test::q(vxl), test::q(vxlz), test::q(vxl) + " " + test::q(vxlz)})
    for (const std::string option : {"--voxel-size 3", "--memory-limit 64M"}) {
      const test::CommandResult r = test::run_program(VOXVIEW_CLI, inputs + " " + option + render);
      EXPECT_EQ(r.exit_code, 2) << inputs << " " << option << ": " << r.output;
      EXPECT_NE(r.output.find(option.substr(0, option.find(' ')) + " applies to a source tractogram"),
                std::string::npos)
          << r.output;
      EXPECT_FALSE(std::filesystem::exists(dir.file("o.png")));
    }
  const test::CommandResult mixed =
      test::run_program(VOXVIEW_CLI, test::q(vxl) + " " + test::q(tck) + " --voxel-size 3" + render);
  EXPECT_EQ(mixed.exit_code, 0) << mixed.output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("o.png")));
}

// A colour option of another colour mode changes nothing in a picture drawn headless: a note says so, and the
// picture is drawn; with --save-camera it is kept in the saved view, and nothing is said.
TEST(VoxviewCommandLine, ColourOptionsOfAnotherColourModeAreNotedHeadless) {
  test::ScratchDir dir;
  const std::string render = small_source_rendered(dir);
  const test::CommandResult r = test::run_program(VOXVIEW_CLI, render + " --colormap hot --fixed-color '#ff0000'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("note: --colormap goes with --color scalar; this picture is coloured by direction"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("note: --fixed-color goes with --color fixed"), std::string::npos) << r.output;
  // A group's colour is the group mode's; its opacity applies in every mode, so an opacity alone is not noted. (The
  // TCK, converted on the fly, is the group named after it.)
  const test::CommandResult group_colour = test::run_program(VOXVIEW_CLI, render + " --group 'a.tck=#00ff00:0.5'");
  EXPECT_EQ(group_colour.exit_code, 0) << group_colour.output;
  EXPECT_NE(group_colour.output.find("note: --group a.tck=#00ff00:0.5: its colour goes with --color group; this "
                                     "picture is coloured by direction (its opacity applies)"),
            std::string::npos)
      << group_colour.output;
  for (const char* quiet : {" --group 'a.tck=:0.2'", " --color group --group 'a.tck=#00ff00:0.5'"}) {
    const test::CommandResult r2 = test::run_program(VOXVIEW_CLI, render + quiet);
    EXPECT_EQ(r2.exit_code, 0) << quiet << ": " << r2.output;
    EXPECT_EQ(r2.output.find("note:"), std::string::npos) << quiet << ": " << r2.output;
  }
  const test::CommandResult fixed = test::run_program(VOXVIEW_CLI, render + " --color fixed --fixed-color '#ff0000'");
  EXPECT_EQ(fixed.exit_code, 0) << fixed.output;
  EXPECT_EQ(fixed.output.find("note:"), std::string::npos) << fixed.output;
  // Scalar colours the points without a value in the fixed colour: nothing to say of --fixed-color there.
  test::VxlBytes::make(dir.file("v.vxl"));  // per-point values
  const test::CommandResult scalar =
      test::run_program(VOXVIEW_CLI, test::q(dir.file("v.vxl")) + " --size 16x16 --render " +
                                         test::q(dir.file("v.png")) + " --color scalar --fixed-color '#ff0000'");
  EXPECT_EQ(scalar.exit_code, 0) << scalar.output;
  EXPECT_EQ(scalar.output.find("note:"), std::string::npos) << scalar.output;
  const test::CommandResult saved =
      test::run_program(VOXVIEW_CLI, render + " --colormap hot --save-camera " + test::q(dir.file("v.json")));
  EXPECT_EQ(saved.exit_code, 0) << saved.output;
  EXPECT_EQ(saved.output.find("note:"), std::string::npos) << saved.output;
}

// --render with --stats: where the time from the process start to each picture went, and what the GPU was sent.
TEST(VoxviewCommandLine, RenderWithStatsSaysWhereTheTimeWentAndWhatWasUploaded) {
  test::ScratchDir dir;
  ASSERT_EQ(test::run_cli("synth " + test::q(dir.file("a.tck")) + " --streamlines 300").exit_code, 0);
  ASSERT_EQ(test::run_cli("convert " + test::q(dir.file("a.tck")) + " " + test::q(dir.file("a.vxl"))).exit_code, 0);
  const test::CommandResult r =
      test::run_program(VOXVIEW_CLI, test::q(dir.file("a.vxl")) + " --size 64x48 --level 0 --turntable 2 --render " +
                                         test::q(dir.file("a.png")) + " --stats " + test::q(dir.file("s.json")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::vector<char> text = test::slurp(dir.file("s.json"));
  const nlohmann::json j = nlohmann::json::parse(text);
  // The summary first, the pictures' list last.
  const std::string_view view(text.data(), text.size());
  EXPECT_LT(view.find("\"upload\""), view.find("\"pictures\"")) << view;
  EXPECT_LT(view.find("\"first_picture_written_s\""), view.find("\"pictures\"")) << view;
  EXPECT_EQ(j.at("mode"), "axis");
  EXPECT_EQ(j.at("size"), nlohmann::json::array({64, 48}));
  EXPECT_EQ(j.at("level"), 0);
  EXPECT_FALSE(j.at("gl_renderer").get<std::string>().empty());
  // Each step after the one before it.
  const auto& startup = j.at("startup");
  double before = 0;
  for (const char* step : {"main_s", "files_open_s", "context_s", "scene_ready_s"}) {
    EXPECT_GE(startup.at(step).get<double>(), before) << step;
    before = startup.at(step).get<double>();
  }
  const auto& pictures = j.at("pictures");
  ASSERT_EQ(pictures.size(), 2u) << "one a turntable frame";
  EXPECT_EQ(j.at("first_picture_written_s"), pictures[0].at("written_s"));
  for (const auto& p : pictures) {
    // Its steps come one after the other, between the step before it and its writing.
    double steps_ms = 0;
    for (const char* step : {"draw_ms", "read_back_ms", "checks_wait_ms", "write_ms"}) {
      EXPECT_GE(p.at(step).get<double>(), 0.0) << step;
      steps_ms += p.at(step).get<double>();
    }
    EXPECT_GT(p.at("draw_ms").get<double>(), 0.0);
    EXPECT_GT(p.at("write_ms").get<double>(), 0.0) << "a file was written";
    EXPECT_GE(p.at("written_s").get<double>() - before, 0.999 * steps_ms / 1000);
    before = p.at("written_s").get<double>();
    EXPECT_GT(p.at("segments").get<std::uint64_t>(), 0u);
  }
  // The whole file at level 0 was uploaded once: its positions and orders at least, and no more than the layout says
  // a full copy can take.
  std::uint64_t least = 0, most = 0, spans = 0;
  {
    HeadlessGlContext context;
    const VxlFile file = VxlFile::open(dir.file("a.vxl"));
    const SceneLayout layout(file, GpuScene::driver_limit(), 0);
    for (const TextureSpan& span : layout.texture_spans()) least += 4 * (span.words() + span.order_words);
    most = layout.upload_bytes();
    spans = layout.texture_spans().size();
  }
  const auto& upload = j.at("upload");
  EXPECT_GE(upload.at("bytes").get<std::uint64_t>(), least);
  EXPECT_LE(upload.at("bytes").get<std::uint64_t>(), most);
  EXPECT_EQ(upload.at("spans").get<std::uint64_t>(), spans) << "each uploaded once";
  EXPECT_GT(upload.at("seconds").get<double>(), 0.0);
  EXPECT_GT(upload.at("gb_per_s").get<double>(), 0.0);
}

}  // namespace
}  // namespace vxl
