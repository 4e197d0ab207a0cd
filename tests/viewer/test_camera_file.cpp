// Batch figures: saved views (--save-camera / --camera) round-trip exactly and replay the same picture;
// --turntable writes N frames around the vertical axis, frame 0 being the plain render.
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "tests/test_support.h"
#include "viewer/app/camera_file.h"
#include "viewer/app/turntable.h"
#include "viewer/platform/image_io.h"

namespace vxl {
namespace {

using app::SavedView;
using test::ScratchDir;

SavedView unusual_view() {
  SavedView v;
  v.camera.target = {1e5 + 0.1, -3.25, 1.0 / 3.0};
  v.camera.distance = 123.456789012345;
  v.camera.azimuth_deg = -170.1;
  v.camera.elevation_deg = 33.3;
  v.camera.fov_y_deg = 41;
  v.camera.orthographic = true;
  v.camera.ortho_height = 77.7;
  RenderSettings& s = v.settings;
  s.mode = RenderMode::Wboit;
  s.opacity = 0.123f;
  s.color = ColorMode::Scalar;
  s.fixed_color = {0.1f, 0.2f, 0.3f};
  s.colormap = Colormap::Hot;
  s.scalar = "fa";
  s.range = std::array<float, 2>{0.1f, 0.9f};
  s.group_styles = {{"ARC_L", glm::vec3(1, 0, 0), 0.25f}, {"ARC_R", std::nullopt, 0.0f}};
  s.line_width = 2.5f;
  s.background_color = {0.1f, 0.2f, 0.3f};  // no #RRGGBB says it exactly
  s.orientation_labels = true;
  s.colorbar = true;
  s.lighting = true;
  s.order_hysteresis = 0.05f;
  s.clipping.slab_mm = 12.5;
  s.clipping.planes = {*parse_axis_clip("-x,10.25"), *parse_axis_clip("z,-1e-3")};
  s.clipping.planes[1].enabled = false;
  v.size = std::array<int, 2>{640, 480};
  return v;
}

TEST(CameraFile, RoundTripsEveryFieldExactly) {
  const SavedView a = unusual_view();
  const SavedView b = app::parse_view_json(app::view_json(a), "mem.json");
  EXPECT_EQ(b.camera.target, a.camera.target);
  EXPECT_EQ(b.camera.distance, a.camera.distance);
  EXPECT_EQ(b.camera.azimuth_deg, a.camera.azimuth_deg);
  EXPECT_EQ(b.camera.elevation_deg, a.camera.elevation_deg);
  EXPECT_EQ(b.camera.fov_y_deg, a.camera.fov_y_deg);
  EXPECT_EQ(b.camera.orthographic, a.camera.orthographic);
  EXPECT_EQ(b.camera.ortho_height, a.camera.ortho_height);
  const RenderSettings &s = a.settings, &t = b.settings;
  EXPECT_EQ(t.mode, s.mode);
  EXPECT_EQ(t.opacity, s.opacity);
  EXPECT_EQ(t.color, s.color);
  EXPECT_EQ(t.fixed_color, s.fixed_color);
  EXPECT_EQ(t.colormap, s.colormap);
  EXPECT_EQ(t.scalar, s.scalar);
  EXPECT_EQ(t.range, s.range);
  ASSERT_EQ(t.group_styles.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(t.group_styles[i].name, s.group_styles[i].name);
    EXPECT_EQ(t.group_styles[i].color, s.group_styles[i].color);
    EXPECT_EQ(t.group_styles[i].opacity, s.group_styles[i].opacity);
  }
  EXPECT_EQ(t.line_width, s.line_width);
  EXPECT_EQ(t.background_color, s.background_color);
  EXPECT_EQ(t.orientation_labels, s.orientation_labels);
  EXPECT_EQ(t.colorbar, s.colorbar);
  EXPECT_EQ(t.lighting, s.lighting);
  EXPECT_EQ(t.order_hysteresis, s.order_hysteresis);
  EXPECT_EQ(t.clipping.slab_mm, s.clipping.slab_mm);
  ASSERT_EQ(t.clipping.planes.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(t.clipping.planes[i].axis, s.clipping.planes[i].axis);
    EXPECT_EQ(t.clipping.planes[i].keep_above, s.clipping.planes[i].keep_above);
    EXPECT_EQ(t.clipping.planes[i].position, s.clipping.planes[i].position);
    EXPECT_EQ(t.clipping.planes[i].enabled, s.clipping.planes[i].enabled);
  }
  EXPECT_EQ(b.size, a.size);
}

// A view with a selection keeps its regions; one without writes no "selection" key.
TEST(CameraFile, TheSelectionsRegionsAndTheirShellsRoundTrip) {
  SavedView a = unusual_view();
  a.include = {"-9,-23,-30,6", "box:0,0,0,1,1,1"};
  a.exclude = {"atlas.nii.gz:3"};
  a.ends_in = {"1,2,3,4"};
  a.show_regions = true;
  const SavedView b = app::parse_view_json(app::view_json(a), "mem.json");
  EXPECT_EQ(b.include, a.include);
  EXPECT_EQ(b.exclude, a.exclude);
  EXPECT_EQ(b.ends_in, a.ends_in);
  EXPECT_EQ(b.show_regions, std::optional<bool>(true));
  // A file written before the key existed says nothing; a wrong type names the key.
  EXPECT_FALSE(app::parse_view_json(R"({"voxview_view": 1, "selection": {"include": ["1,2,3,4"]}})", "old.json")
                   .show_regions.has_value());
  try {
    app::parse_view_json(R"({"voxview_view": 1, "selection": {"show_regions": 1}})", "bad.json");
    ADD_FAILURE() << "a number was taken for show_regions";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("selection.show_regions"), std::string::npos) << e.what();
  }
  EXPECT_EQ(app::view_json(unusual_view()).find("selection"), std::string::npos);
  try {
    app::parse_view_json(R"({"voxview_view": 1, "selection": {"include": [3]}})", "bad.json");
    ADD_FAILURE() << "a number was taken for a region";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("selection.include"), std::string::npos) << e.what();
  }
}

TEST(CameraFile, MissingKeysKeepDefaultsAndBadOnesNameFileAndKey) {
  SavedView defaults;
  defaults.settings.opacity = 0.7f;
  SavedView v = app::parse_view_json(R"({"voxview_view": 1, "settings": {"lighting": true}, "future_key": 3})",
                                     "v.json", defaults);
  EXPECT_TRUE(v.settings.lighting);
  EXPECT_EQ(v.settings.opacity, 0.7f);
  EXPECT_FALSE(v.size);

  auto error_of = [](const std::string& text) -> std::string {
    try {
      app::parse_view_json(text, "bad.json");
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_NE(error_of("[1]").find("bad.json"), std::string::npos);
  EXPECT_NE(error_of(R"({"camera": {}})").find("voxview_view"), std::string::npos);
  EXPECT_NE(error_of(R"({"voxview_view": 2})").find("version 2"), std::string::npos);
  const std::string mode = error_of(R"({"voxview_view": 1, "settings": {"mode": "fancy"}})");
  EXPECT_NE(mode.find("bad.json"), std::string::npos) << mode;
  EXPECT_NE(mode.find("settings.mode"), std::string::npos) << mode;
  EXPECT_NE(error_of(R"({"voxview_view": 1, "camera": {"distance": -1}})").find("camera.distance"), std::string::npos);
  EXPECT_NE(error_of(R"({"voxview_view": 1, "camera": {"target": [1, 2]}})").find("camera.target"), std::string::npos);
  EXPECT_NE(error_of(R"({"voxview_view": 1, "settings": {"clip": [{"plane": "w,1"}]}})").find("settings.clip[0].plane"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"voxview_view": 1, "size": [0, 10]})").find("size"), std::string::npos);
  EXPECT_NE(error_of(R"({"voxview_view": 1, "settings": {"range": [2, 1]}})").find("settings.range"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"voxview_view": 1, "settings": {"groups": [{"name": "A", "color": "red"}]}})")
                .find("settings.groups[0].color"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"voxview_view": 1, "settings": {"colormap": "jet"}})").find("settings.colormap"),
            std::string::npos);
  const std::string background = error_of(R"({"voxview_view": 1, "settings": {"background": "purple"}})");
  EXPECT_NE(background.find("settings.background"), std::string::npos) << background;
  EXPECT_NE(background.find("#RRGGBB"), std::string::npos) << background;
  EXPECT_NE(error_of(R"({"voxview_view": 1, "settings": {"colorbar": 1}})").find("settings.colorbar"),
            std::string::npos);
  // A file written before any colour but black and white still reads.
  EXPECT_EQ(app::parse_view_json(R"({"voxview_view": 1, "settings": {"background": "white"}})", "old.json")
                .settings.background_color,
            glm::vec3(1.0f));

  // Nested 100000 deep, deep enough to overflow the stack of a recursive parse: refused before it is parsed.
  const std::string deep =
      error_of(R"({"voxview_view": 1, "x": )" + std::string(100000, '[') + std::string(100000, ']') + "}");
  EXPECT_NE(deep.find("bad.json: at byte " + std::to_string(25 + kMaxJsonDepth - 1) +
                      ": view file: JSON nested deeper than " + std::to_string(kMaxJsonDepth)),
            std::string::npos)
      << deep;

  ScratchDir dir;
  try {
    app::read_view(dir.file("missing.json"));
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.json"), std::string::npos);
  }
}

// A view file's camera or slab beyond what draws a picture (ViewLimits) is refused, not drawn as nothing.
TEST(CameraFile, CamerasAndSlabsThatDrawNothingAreRefused) {
  auto error_of = [](const std::string& inner) -> std::string {
    try {
      app::parse_view_json(R"({"voxview_view": 1, )" + inner + "}", "v.json");
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
      return e.what();
    }
    return "no error";
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"("camera": {"distance": 1e308})", "camera.distance: expected mm in [0.001, 1e+07]"},
      {R"("camera": {"distance": 1e-300})", "camera.distance"},
      {R"("camera": {"ortho_height": 1e308})", "camera.ortho_height"},
      {R"("camera": {"azimuth_deg": 1e308})", "camera.azimuth_deg: expected degrees within +-1e+06"},
      {R"("camera": {"target": [0, 1e308, 0]})", "camera.target"},
      {R"("camera": {"fov_y_deg": 1e-300})", "camera.fov_y_deg: expected degrees in [1, 179]"},
      {R"("camera": {"fov_y_deg": 179.99999})", "camera.fov_y_deg"},
      {R"("settings": {"slab_mm": 1e-300})", "settings.slab_mm: expected a thickness in [0.001, 1e+07] mm"},
      {R"("settings": {"slab_mm": 1e308})", "settings.slab_mm"},
  };
  for (const auto& [inner, message] : cases)
    EXPECT_NE(error_of(inner).find("v.json: " + message), std::string::npos) << inner << ": " << error_of(inner);
  for (const char* fine : {R"("camera": {"distance": 1e6, "azimuth_deg": -720, "fov_y_deg": 179})",
                           R"("settings": {"slab_mm": 0})", R"("settings": {"slab_mm": 0.5})"})
    EXPECT_EQ(error_of(fine), "no error") << fine;
}

TEST(CameraFile, TurntableFrameNames) {
  EXPECT_EQ(app::turntable_frame_path("out/fig.png", 0, 36), "out/fig_000.png");
  EXPECT_EQ(app::turntable_frame_path("fig.png", 35, 36), "fig_035.png");
  EXPECT_EQ(app::turntable_frame_path("fig.png", 1234, 2000), "fig_1234.png");
  EXPECT_EQ(app::turntable_frame_path("fig.png", 12, 2000), "fig_0012.png");
  EXPECT_EQ(app::turntable_frame_path("fig", 1, 2), "fig_001.png");
  Camera c;
  c.azimuth_deg = 30;
  c.elevation_deg = 20;
  EXPECT_EQ(app::turntable_camera(c, 0, 4).azimuth_deg, 30);
  EXPECT_EQ(app::turntable_camera(c, 3, 4).azimuth_deg, 300);
  EXPECT_EQ(app::turntable_camera(c, 3, 4).elevation_deg, 20);
}

class BatchFigures : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(std::filesystem::exists(VOXVIEW_CLI)) << VOXVIEW_CLI;
    auto synth = test::run_cli("synth --streamlines 200 --seed 5 '" + dir.file("s.tck") + "'");
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    auto convert = test::run_cli("convert '" + dir.file("s.tck") + "' '" + vxl + "'");
    ASSERT_EQ(convert.exit_code, 0) << convert.output;
  }
  test::CommandResult voxview(const std::string& args) {
    return test::run_program(VOXVIEW_CLI, "'" + vxl + "' " + args);
  }
  Image image(const std::string& name) { return read_image(dir.file(name)); }
  std::string at(const std::string& name) { return "'" + dir.file(name) + "'"; }

  ScratchDir dir;
  std::string vxl = dir.file("s.vxl");
};

TEST_F(BatchFigures, ASavedViewReplaysTheSamePicture) {
  auto first = voxview("--render " + at("a.png") + " --save-camera " + at("v.json") +
                       " --size 96x64 --view 30,20 --opacity 0.7 --mode basic --color fixed --background white"
                       " --line-width 2 --lighting --slab 40 --clip -x,5");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  auto replay = voxview("--render " + at("b.png") + " --camera " + at("v.json"));
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  const Image a = image("a.png"), b = image("b.png");
  ASSERT_EQ(b.width, 96);  // the size comes from the view file too
  ASSERT_EQ(b.height, 64);
  EXPECT_EQ(compare_images(a, b).differing_pixels, 0u);

  // The saved view really carries the settings: without the file, the picture differs.
  auto plain = voxview("--render " + at("c.png") + " --size 96x64 --view 30,20");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_GT(compare_images(a, image("c.png")).differing_pixels, 200u);
  // Options given with --camera override it.
  auto changed = voxview("--render " + at("d.png") + " --camera " + at("v.json") + " --opacity 0.05");
  ASSERT_EQ(changed.exit_code, 0) << changed.output;
  EXPECT_GT(compare_images(a, image("d.png")).differing_pixels, 50u);

  std::ofstream(dir.file("broken.json")) << R"({"voxview_view": 1, "settings": {"opacity": "high"}})";
  auto broken = voxview("--render " + at("e.png") + " --camera " + at("broken.json"));
  EXPECT_EQ(broken.exit_code, 3);
  EXPECT_NE(broken.output.find("broken.json"), std::string::npos) << broken.output;
  EXPECT_NE(broken.output.find("settings.opacity"), std::string::npos) << broken.output;
}

TEST_F(BatchFigures, TurntableFramesTurnAroundTheVerticalAxis) {
  auto turn =
      voxview("--render " + at("t.png") + " --turntable 4 --size 64x64 --view 30,20 --save-camera " + at("v.json"));
  ASSERT_EQ(turn.exit_code, 0) << turn.output;
  std::vector<Image> frames;
  for (int i = 0; i < 4; ++i) frames.push_back(image("t_00" + std::to_string(i) + ".png"));
  EXPECT_FALSE(std::filesystem::exists(dir.file("t.png")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("t_004.png")));
  // A turntable is framed for all its frames at once (so that each is whole), not like a single view: frame 0
  // is its saved start view.
  auto plain = voxview("--render " + at("p.png") + " --size 64x64 --camera " + at("v.json"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_EQ(compare_images(frames[0], image("p.png")).differing_pixels, 0u);
  // Frame 2 is the view from the opposite side, azimuth + 180.
  auto opposite = voxview("--render " + at("o.png") + " --size 64x64 --camera " + at("v.json") + " --view 210,20");
  ASSERT_EQ(opposite.exit_code, 0) << opposite.output;
  EXPECT_EQ(compare_images(frames[2], image("o.png")).differing_pixels, 0u);
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      EXPECT_GT(compare_images(frames[i], frames[j]).differing_pixels, 100u) << i << " " << j;

  auto without_render = voxview("--turntable 4");
  EXPECT_EQ(without_render.exit_code, 2);
  EXPECT_NE(without_render.output.find("--render"), std::string::npos) << without_render.output;
}

}  // namespace
}  // namespace vxl
