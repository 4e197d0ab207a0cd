// Several tractograms at once: their voxels are sorted together back to front (interleaved across files, not
// file after file), one group per file for colour and opacity.
#include <filesystem>

#include "tests/viewer/render_support.h"
#include "viewer/render/scene_groups.h"

namespace vxl {
namespace {

using test::gl_context;
using test::render_image;
using test::ScratchDir;

// Four 40 mm lines crossing above (0.5, 0.5), the centre of pixel (32, 31), at depths 15, 5, -5, -15 (10 mm
// apart: in non-neighbouring 5 mm voxels). File A holds those at 15 and -5, file B those at 5 and -15, so
// the right order from above alternates between the files: B(-15), A(-5), B(5), A(15).
// Line k (counted from `first`) runs along x, y, (1, 1), (1, -1), so that lines in different files need not
// cover each other from above.
Tractogram lines_at(std::initializer_list<double> depths, const char* name, int first = 0) {
  Tractogram t;
  int k = first;
  for (double z : depths) {
    const float zf = static_cast<float>(z);
    // Different directions, so that every line has its own colour by direction too.
    const float d[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
    const float dx = d[k % 4][0] * 20, dy = d[k % 4][1] * 20;
    const float p[] = {0.5f - dx, 0.5f - dy, zf, 0.5f + dx, 0.5f + dy, zf};
    t.add_streamline(p, 2);
    ++k;
  }
  t.source.path = name;
  return t;
}

VxlFile convert(const ScratchDir& dir, Tractogram t, const std::string& name, const std::string& orders = "axis") {
  ConvertSettings s;
  s.voxel_size = 5;
  s.orders = orders;
  convert_tractogram(std::move(t), dir.file(name), s);
  return VxlFile::open(dir.file(name));
}

using test::top_view;

RenderSettings settings(RenderMode mode, ColorMode color = ColorMode::Group) {
  RenderSettings s;
  s.mode = mode;
  s.color = color;
  s.opacity = 0.5f;
  return s;
}

const std::uint8_t* centre(const Image& img) { return img.pixel(32, 31); }

glm::dvec3 over(std::initializer_list<glm::dvec3> far_to_near, double alpha) {
  glm::dvec3 c(0.0);
  for (const glm::dvec3& f : far_to_near) c = f * alpha + c * (1 - alpha);
  return c;
}

class SeveralFiles : public ::testing::Test {
 protected:
  void SetUp() override { gl_context(); }
  ScratchDir dir;
};

TEST_F(SeveralFiles, VoxelsOfAllFilesAreSortedTogether) {
  VxlFile a = convert(dir, lines_at({15, -5}, "A"), "a.vxl"), b = convert(dir, lines_at({5, -15}, "B"), "b.vxl");
  Renderer r({&a, &b});
  ASSERT_EQ(r.groups().groups().size(), 2u);
  EXPECT_EQ(r.groups().groups()[0].name, "a.vxl");
  EXPECT_EQ(r.groups().groups()[1].name, "b.vxl");

  const glm::dvec3 ca(group_palette(0)), cb(group_palette(1));
  const glm::dvec3 right = over({cb, ca, cb, ca}, 0.5);
  // What drawing the files one after the other would give (each sorted, A first or B first).
  const glm::dvec3 a_then_b = over({ca, ca, cb, cb}, 0.5), b_then_a = over({cb, cb, ca, ca}, 0.5);
  ASSERT_GT(glm::length(right - a_then_b) * 255, 20);
  ASSERT_GT(glm::length(right - b_then_a) * 255, 20);

  Image axis = render_image(r, top_view(), settings(RenderMode::Axis), 64, 64);
  EXPECT_EQ(r.stats().voxels_drawn, a.meta().voxel_count + b.meta().voxel_count);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(centre(axis)[c], right[c] * 255, 1.0) << "channel " << c;
  Image exact = render_image(r, top_view(), settings(RenderMode::Exact), 64, 64);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(centre(exact)[c], right[c] * 255, 1.0) << "channel " << c;

  // The files' order on the command line does not change the picture.
  Renderer reversed({&b, &a});
  RenderSettings swapped = settings(RenderMode::Axis);
  swapped.style_of("a.vxl").color = glm::vec3(ca);  // a.vxl is group 1 now: keep its colour
  swapped.style_of("b.vxl").color = glm::vec3(cb);
  Image r_axis = render_image(reversed, top_view(), swapped, 64, 64);
  EXPECT_LE(compare_images(axis, r_axis).max_error * 255, 1.01);

  // The same as one file holding all four lines, by direction colour.
  VxlFile all = convert(dir, lines_at({15, -5, 5, -15}, "all"), "all.vxl");
  Renderer one(all);
  VxlFile b2 = convert(dir, lines_at({5, -15}, "B", 2), "b2.vxl");
  Renderer two({&a, &b2});
  Image single = render_image(one, top_view(), settings(RenderMode::Axis, ColorMode::Direction), 64, 64);
  Image pair = render_image(two, top_view(), settings(RenderMode::Axis, ColorMode::Direction), 64, 64);
  EXPECT_LE(compare_images(single, pair).max_error * 255, 1.01);
}

TEST_F(SeveralFiles, FilesWithDifferentOrderSetsAndGroupOpacity) {
  VxlFile a = convert(dir, lines_at({15, -5}, "A"), "a.vxl", "axis+diag");
  VxlFile b = convert(dir, lines_at({5, -15}, "B"), "b.vxl", "random:4");
  // Texture buffers as small as the largest voxel: several spans per file.
  Renderer r({&a, &b}, SceneLayout::largest_voxel_texels(std::vector<const VxlFile*>{&a, &b}));
  EXPECT_GT(r.layout().texture_spans().size(), 2u);
  Image axis = render_image(r, top_view(), settings(RenderMode::Axis), 64, 64);
  Image exact = render_image(r, top_view(), settings(RenderMode::Exact), 64, 64);
  EXPECT_LE(compare_images(axis, exact).max_error * 255, 1.01);
  Image unsorted = render_image(r, top_view(), settings(RenderMode::Unsorted), 64, 64);
  EXPECT_GT(compare_images(unsorted, exact).max_error * 255, 10) << "dataset order is file after file: wrong here";

  // One file hidden: the other alone, as if opened by itself.
  RenderSettings s = settings(RenderMode::Axis);
  s.style_of("a.vxl").opacity = 0;
  Image only_b = render_image(r, top_view(), s, 64, 64);
  Renderer alone(b);
  RenderSettings sb = settings(RenderMode::Axis);
  sb.style_of("b.vxl").color = glm::vec3(group_palette(1));
  Image b_alone = render_image(alone, top_view(), sb, 64, 64);
  EXPECT_LE(compare_images(only_b, b_alone).max_error * 255, 1.01);
}

TEST_F(SeveralFiles, VoxviewOpensSeveralFiles) {
  ASSERT_TRUE(std::filesystem::exists(VOXVIEW_CLI)) << VOXVIEW_CLI;
  convert(dir, lines_at({15, -5}, "A"), "a.vxl");
  convert(dir, lines_at({5, -15}, "B", 2), "b.vxl");  // diagonals: seen from above next to A's lines
  const std::string files = "'" + dir.file("a.vxl") + "' '" + dir.file("b.vxl") + "'";
  const std::string png = dir.file("out.png");
  auto count = [](const Image& img, const glm::vec3& rgb) {
    int n = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        bool near = true;
        for (int k = 0; k < 3; ++k) near &= std::abs(img.pixel(x, y)[k] - rgb[k] * 255.0f) <= 2;
        n += near;
      }
    return n;
  };
  auto r = test::run_program(
      VOXVIEW_CLI, files + " --render '" + png + "' --size 96x96 --mode opaque --color group --view axial --ortho");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("voxels"), std::string::npos);
  Image both = read_image(png);
  EXPECT_GT(count(both, group_palette(0)), 40);
  EXPECT_GT(count(both, group_palette(1)), 40);
  r = test::run_program(VOXVIEW_CLI,
                        files + " --render '" + png + "' --size 96x96 --mode opaque --color group --group 'b.vxl=:0'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  Image only_a = read_image(png);
  EXPECT_GT(count(only_a, group_palette(0)), 40);
  EXPECT_EQ(count(only_a, group_palette(1)), 0);
  auto tsf = test::run_program(VOXVIEW_CLI, files + " --tsf x.tsf --render '" + png + "'");
  EXPECT_EQ(tsf.exit_code, 2);
  EXPECT_NE(tsf.output.find("single input"), std::string::npos) << tsf.output;
}

}  // namespace
}  // namespace vxl
