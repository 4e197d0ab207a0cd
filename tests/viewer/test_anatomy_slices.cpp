// An anatomical image under the lines (--image): NIfTI files written here with nifti_clib, a known bright
// cube in them; the slices must show it where the sform / qform puts it, hide the lines behind them and
// lie under the lines in front, in every transparency mode; bad files are refused naming the file.
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <nifti2_io.h>

#include "converter/readers/volume_image.h"
#include "format/base/error.h"
#include "tests/viewer/render_support.h"
#include "viewer/anatomy/nifti_volume.h"

namespace vxl {
namespace {

using test::gl_context;
using test::make_scene;
using test::render_image;
using test::ScratchDir;

// 64^3 voxels of 1 mm covering RAS [-32, 32]^3. Values: 300 in the "head" box |x|, |y|, |z| < 20, 1000 in
// the cube [4, 20)^3 inside it (upper right front, so that a flipped axis shows), 0 elsewhere. Stored
// with x reversed (voxel i at x = 31.5 - i), which only the right transform undoes.
constexpr int kN = 64;
float true_value(double x, double y, double z) {
  if (x >= 4 && x < 20 && y >= 4 && y < 20 && z >= 4 && z < 20) return 1000;
  if (std::abs(x) < 20 && std::abs(y) < 20 && std::abs(z) < 20) return 300;
  return 0;
}

struct NiftiSpec {
  bool nifti2 = false;
  bool use_sform = true;      // else the qform (sform_code 0, and a wrong sform to make sure it is ignored)
  bool int16_scaled = false;  // int16 stored as (value - 100) / 2 with scl_slope 2, scl_inter 100
  std::string suffix = ".nii";
};

std::string write_nifti(const ScratchDir& dir, const std::string& name, const NiftiSpec& spec = {}) {
  const int64_t dims[8] = {3, kN, kN, kN, 1, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, spec.int16_scaled ? DT_INT16 : DT_FLOAT32, 1);
  for (int k = 0; k < kN; ++k)
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) {
        const float v = true_value(31.5 - i, j - 31.5, k - 31.5);
        const std::size_t at = (std::size_t(k) * kN + j) * kN + i;
        if (spec.int16_scaled)
          static_cast<int16_t*>(nim->data)[at] = static_cast<int16_t>((v - 100) / 2);
        else
          static_cast<float*>(nim->data)[at] = v;
      }
  if (spec.int16_scaled) nim->scl_slope = 2, nim->scl_inter = 100;
  nifti_dmat44 m;
  for (auto& row : m.m)
    for (double& x : row) x = 0;
  m.m[0][0] = -1, m.m[0][3] = 31.5;
  m.m[1][1] = 1, m.m[1][3] = -31.5;
  m.m[2][2] = 1, m.m[2][3] = -31.5;
  m.m[3][3] = 1;
  if (spec.use_sform) {
    nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
    nim->sto_xyz = m;
    nim->qform_code = 0;
  } else {
    nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
    nim->qto_xyz = m;
    nifti_dmat44_to_quatern(m, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d, &nim->qoffset_x, &nim->qoffset_y,
                            &nim->qoffset_z, nullptr, nullptr, nullptr, &nim->qfac);
    nim->sform_code = 0;  // an identity sform would put the cube elsewhere; a code of 0 says: ignore it
  }
  nim->xyz_units = NIFTI_UNITS_MM;
  nim->nifti_type = spec.nifti2 ? NIFTI_FTYPE_NIFTI2_1 : NIFTI_FTYPE_NIFTI1_1;
  const std::string path = dir.file(name + spec.suffix);
  EXPECT_EQ(nifti_set_filenames(nim, path.c_str(), 0, 1), 0);
  nifti_image_write(nim);
  nifti_image_free(nim);
  EXPECT_TRUE(std::filesystem::exists(path)) << path;
  return path;
}

// Seen from above (anterior up, right on the right) on a 64 x 64 image at 1 mm per pixel: world (x, y) =
// (c - 31.5, 31.5 - r) at the centre of pixel (c, r); the focus (the axial slice) at height z.
Camera top_view_at(double z) {
  Camera c = test::top_view();
  c.target = {0, 0, z};
  return c;
}
using test::column_of;
using test::row_of;

// Two red lines along x: one 10 mm above the axial slice at z = 0 (in front, seen from above) on row
// y = 8.5, one 10 mm below it (behind) on row y = -7.5.
Tractogram front_and_back() {
  Tractogram t;
  const float front[] = {-19.5f, 8.5f, 10.0f, 20.5f, 8.5f, 10.0f};
  const float back[] = {-19.5f, -7.5f, -10.0f, 20.5f, -7.5f, -10.0f};
  t.add_streamline(front, 2);
  t.add_streamline(back, 2);
  t.source.path = "front_and_back";
  return t;
}

RenderSettings axial_only() {
  RenderSettings s;
  s.slices.axial = true;
  s.slices.coronal = s.slices.sagittal = false;
  s.slices.range = std::array<float, 2>{0, 1000};  // the head grey (77), the cube white, outside black
  s.color = ColorMode::Fixed;
  s.fixed_color = {1, 0, 0};
  return s;
}

int grey(const Image& img, double x, double y) { return img.pixel(column_of(x), row_of(y))[0]; }

class AnatomySlices : public ::testing::Test {
 protected:
  void SetUp() override { gl_context(); }
  ScratchDir dir;
};

TEST_F(AnatomySlices, ReaderScalesAndWindows) {
  for (const NiftiSpec& spec : {NiftiSpec{}, NiftiSpec{true, false, true, ".nii.gz"}}) {
    const Volume v = read_nifti_volume(write_nifti(dir, spec.nifti2 ? "two" : "one", spec));
    ASSERT_EQ(v.dims[0], kN);
    // Voxel (i, j, k) = (20, 40, 40) is at x = 11.5, y = z = 8.5: in the cube.
    const glm::dvec3 p(v.voxel_to_ras * glm::dvec4(20, 40, 40, 1));
    EXPECT_NEAR(p.x, 11.5, 1e-4);
    EXPECT_NEAR(p.y, 8.5, 1e-4);
    EXPECT_EQ(v.values[(40 * kN + 40) * kN + 20], 1000.0f);
    EXPECT_EQ(v.values[(30 * kN + 30) * kN + 30], 300.0f);
    EXPECT_EQ(v.values[0], 0.0f);
    // 2-98 % of the non-zero voxels: 40^3 of the head, 16^3 (6.4 %) of them the cube.
    EXPECT_EQ(v.window[0], 300.0f);
    EXPECT_EQ(v.window[1], 1000.0f);
  }  // Exactly the file named: a T1.nii beside T1.nii.gz is not read in its place (nifti_clib's own search would).
  const std::string gz = write_nifti(dir, "twin", NiftiSpec{false, true, false, ".nii.gz"});
  std::ofstream(dir.file("twin.nii")) << "not the image";
  EXPECT_EQ(read_nifti_volume(gz).window[1], 1000.0f);
}

// The axial slice through the focus shows the cube where the transform puts it: upper right (+x, +y),
// only while the focus is within the cube's heights; hidden, it shows nothing.
TEST_F(AnatomySlices, SliceShowsTheCubeWhereItIs) {
  for (const NiftiSpec& spec :
       {NiftiSpec{}, NiftiSpec{false, false, false, ".nii"}, NiftiSpec{true, true, true, ".nii.gz"}}) {
    SCOPED_TRACE(std::string(spec.use_sform ? "sform" : "qform") + (spec.nifti2 ? " nifti2" : " nifti1"));
    VxlFile scene = make_scene(dir, front_and_back(), 10.0);
    Renderer r(scene);
    // A name of its own for each: given cube.nii.gz, nifti_clib would read a cube.nii beside it.
    const std::string name =
        std::string(spec.use_sform ? "s" : "q") + (spec.nifti2 ? "2" : "1") + (spec.int16_scaled ? "i" : "f");
    r.set_volume(read_nifti_volume(write_nifti(dir, name, spec)));
    RenderSettings s = axial_only();
    s.opacity = 0.001f;  // the lines out of the way
    const Image in = render_image(r, top_view_at(12), s, 64, 64);
    EXPECT_GE(grey(in, 12.5, 12.5), 250);       // the cube
    EXPECT_NEAR(grey(in, -12.5, 12.5), 77, 3);  // mirrored in x: head only
    EXPECT_NEAR(grey(in, 12.5, -12.5), 77, 3);  // mirrored in y
    EXPECT_LE(grey(in, -26.5, 0.5), 1);         // inside the image, outside the head
    const Image below = render_image(r, top_view_at(-12), s, 64, 64);
    EXPECT_NEAR(grey(below, 12.5, 12.5), 77, 3);  // the slice moved with the focus
    s.slices.axial = false;
    const Image hidden = render_image(r, top_view_at(12), s, 64, 64);
    EXPECT_LE(grey(hidden, 12.5, 12.5), 1);
  }
}

// A half-transparent red line in front of the slice blends over its grey, the one behind it is hidden:
// in every mode. Without the depth test the back line would show; compositing over the background
// instead of the slice would lose the grey under the front line.
TEST_F(AnatomySlices, LinesInFrontBlendOverTheSliceLinesBehindAreHidden) {
  VxlFile scene = make_scene(dir, front_and_back(), 10.0);
  Renderer r(scene);
  r.set_volume(read_nifti_volume(write_nifti(dir, "cube")));
  const double g = 0.3;  // the head's grey at z = 0 with the range 0..1000
  for (RenderMode mode : {RenderMode::Opaque, RenderMode::Unsorted, RenderMode::Additive, RenderMode::Wboit,
                          RenderMode::Basic, RenderMode::Axis, RenderMode::Exact}) {
    SCOPED_TRACE(render_mode_name(mode));
    RenderSettings s = axial_only();
    s.mode = mode;
    s.opacity = 0.5f;
    const Image img = render_image(r, top_view_at(0), s, 64, 64);
    // The line's coverage over the slice: opaque replaces; additive mixes its opaque pass (1) and its
    // additive pass (0.5) by the opacity; the others blend at the opacity.
    const double a = mode == RenderMode::Opaque ? 1.0 : mode == RenderMode::Additive ? 0.75 : 0.5;
    for (double x : {-10.0, 0.5, 10.0}) {
      const std::uint8_t* front = img.pixel(column_of(x), row_of(8.5));
      EXPECT_NEAR(front[0], 255 * (a + (1 - a) * g), 3) << "x " << x;
      EXPECT_NEAR(front[1], 255 * (1 - a) * g, 3) << "x " << x;
      EXPECT_NEAR(front[2], 255 * (1 - a) * g, 3) << "x " << x;
      const std::uint8_t* back = img.pixel(column_of(x), row_of(-7.5));
      EXPECT_NEAR(back[0], 255 * g, 2) << "x " << x;
      EXPECT_NEAR(back[1], 255 * g, 2) << "x " << x;
    }
    // With the slices off the back line shows: the test above sees what it means to.
    s.slices.axial = false;
    const Image bare = render_image(r, top_view_at(0), s, 64, 64);
    EXPECT_GT(bare.pixel(column_of(0.5), row_of(-7.5))[0], 100);
  }
}

// With a slab, the slices are cut by it like the lines; the `view` slice lies in the slab's middle, so it
// stays whole in an oblique view where the axial slice shrinks to a strip.
TEST_F(AnatomySlices, SlabShowsTheSliceInItsMiddle) {
  VxlFile scene = make_scene(dir, front_and_back(), 10.0);
  Renderer r(scene);
  r.set_volume(read_nifti_volume(write_nifti(dir, "cube")));
  Camera oblique = top_view_at(0);
  oblique.elevation_deg = 50;
  oblique.azimuth_deg = 150;
  RenderSettings s = axial_only();
  s.opacity = 0.001f;
  auto grey_pixels = [&](const RenderSettings& settings) {
    const Image img = render_image(r, oblique, settings, 64, 64);
    int n = 0;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) n += img.pixel(x, y)[1] > 40;  // the head's grey (77) or the cube
    return n;
  };
  const int axial = grey_pixels(s);
  s.clipping.slab_mm = 4;
  const int axial_in_slab = grey_pixels(s);
  s.slices.axial = false;
  s.slices.view_plane = true;
  const int view_in_slab = grey_pixels(s);
  EXPECT_GT(axial, 600);                // the head's 40 x 40 mm, foreshortened
  EXPECT_LT(axial_in_slab, axial / 4);  // a strip 4 mm / sin(50 deg) wide
  EXPECT_GT(view_in_slab, 1000);        // facing the viewer: the head's 40 x 40 mm, whole
}

class AnatomyCli : public AnatomySlices {
 protected:
  test::CommandResult voxview(const std::string& args) {
    return test::run_program(VOXVIEW_CLI, "'" + dir.file("scene.vxl") + "' --render '" + dir.file("out.png") +
                                              "' --size 64x64 --view axial --ortho --mode opaque " + args);
  }
  void SetUp() override {
    AnatomySlices::SetUp();
    ASSERT_TRUE(std::filesystem::exists(VOXVIEW_CLI)) << VOXVIEW_CLI;
    // Two lines along the image's x and y edges (the view frames them): pure red and green, never grey.
    Tractogram t;
    const float along_x[] = {-30.0f, -30.0f, 0.0f, 30.0f, -30.0f, 0.0f};
    const float along_y[] = {-30.0f, -30.0f, 0.0f, -30.0f, 30.0f, 0.0f};
    t.add_streamline(along_x, 2);
    t.add_streamline(along_y, 2);
    make_scene(dir, t, 10.0);
  }
  // The brightest grey (R = G = B) pixel of the last picture.
  int brightest_grey() {
    const Image img = read_image(dir.file("out.png"));
    int best = -1;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        const std::uint8_t* p = img.pixel(x, y);
        if (p[0] == p[1] && p[1] == p[2]) best = std::max<int>(best, p[0]);
      }
    return best;
  }
};

TEST_F(AnatomyCli, ImageRange) {
  const std::string image = write_nifti(dir, "cube", NiftiSpec{false, true, false, ".nii.gz"});
  auto plain = voxview("--image '" + image + "' --focus 0,0,12 --slices axial");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_EQ(brightest_grey(), 255);  // the default window ends at the cube's 1000
  auto half = voxview("--image '" + image + "' --focus 0,0,12 --slices axial --image-range 0,2000");
  ASSERT_EQ(half.exit_code, 0) << half.output;
  EXPECT_NEAR(brightest_grey(), 128, 2);
  auto off = voxview("--image '" + image + "' --focus 0,0,12 --slices none");
  ASSERT_EQ(off.exit_code, 0) << off.output;
  EXPECT_EQ(brightest_grey(), 0);
  auto focus_below = voxview("--image '" + image + "' --focus 0,0,-12 --slices axial --image-range 0,1000");
  ASSERT_EQ(focus_below.exit_code, 0) << focus_below.output;
  EXPECT_NEAR(brightest_grey(), 77, 2);  // the head, not the cube

  for (const char* bad : {"--image-range 5,1", "--image-range x", "--slices axial,top", "--focus 1,2"}) {
    auto r = voxview("--image '" + image + "' " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.output;
  }
  EXPECT_EQ(voxview("--image-range 0,1").exit_code, 2);  // without --image
}

// The window draws the slices too (under a virtual X server, as the window tests do).
TEST_F(AnatomyCli, WindowShowsTheSlices) {
  if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0) GTEST_SKIP() << "xvfb-run is not installed";
  const std::string image = write_nifti(dir, "cube");
  auto window = [&](const std::string& extra) {
    const std::string cmd = "xvfb-run -a -s \"-screen 0 800x600x24\" '" + std::string(VOXVIEW_CLI) + "' '" +
                            dir.file("scene.vxl") + "' --size 64x64 --frames 2 --screenshot '" + dir.file("out.png") +
                            "' --view axial --ortho --focus 0,0,12 " + "--image '" + image +
                            "' --image-range 0,1000 --slices " + extra;
    return test::run_program(cmd, "");
  };
  auto shown = window("axial");
  ASSERT_EQ(shown.exit_code, 0) << shown.output;
  EXPECT_GE(brightest_grey(), 250);  // the cube
  auto none = window("none");
  ASSERT_EQ(none.exit_code, 0) << none.output;
  EXPECT_EQ(brightest_grey(), 0);
}

// The 3-D texture's limits are the viewer's: the converter's reader takes the same image.
TEST(AnatomyVolume, TextureLimitIsTheViewersOwn) {
  ScratchDir dir;
  const int64_t dims[8] = {3, 2049, 2, 2, 1, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, DT_UINT8, 1);
  nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
  const std::string path = dir.file("wide.nii");
  ASSERT_EQ(nifti_set_filenames(nim, path.c_str(), 0, 1), 0);
  nifti_image_write(nim);
  nifti_image_free(nim);
  EXPECT_EQ(read_volume_image(path).dims[0], 2049);
  try {
    (void)read_nifti_volume(path);
    ADD_FAILURE() << "a 2049-voxel axis was taken";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported) << e.what();
    EXPECT_NE(std::string(e.what()).find("at most 2048 along each axis"), std::string::npos) << e.what();
  }
}

TEST_F(AnatomyCli, BadImagesAreRefusedNamingTheFile) {
  const std::string good = write_nifti(dir, "good");
  const std::string bytes = test::slurp<std::string>(good);
  ASSERT_GT(bytes.size(), 352u + kN * kN * kN * 4 - 1);
  auto write = [&](const std::string& name, const std::string& content) {
    std::ofstream(dir.file(name), std::ios::binary) << content;
    return dir.file(name);
  };
  std::string wrong_magic = bytes;
  wrong_magic[344] = 'x';
  std::string absurd = bytes;  // dim[1] (int16 at byte 42) = 2000: 2000 x 64 x 64 floats
  absurd[42] = static_cast<char>(2000 & 0xFF), absurd[43] = static_cast<char>(2000 >> 8);
  std::string huge = bytes;  // dim[1..3] = 32767 each: 3.5e13 voxels
  for (int at : {42, 44, 46}) huge[at] = static_cast<char>(0xFF), huge[at + 1] = 0x7F;
  std::string negative = bytes;  // dim[2] = -5
  negative[44] = static_cast<char>(-5), negative[45] = static_cast<char>(0xFF);
  // A gzipped file cut short: its data stops in the middle.
  const std::string gz = write_nifti(dir, "zipped", NiftiSpec{false, true, false, ".nii.gz"});
  const std::string gz_bytes = test::slurp<std::string>(gz);
  const std::pair<std::string, std::string> cases[] = {
      {write("truncated.nii", bytes.substr(0, bytes.size() - 1000)), "truncated"},
      {write("header_only.nii", bytes.substr(0, 200)), "truncated NIfTI header"},
      {write("magic.nii", wrong_magic), "magic"},
      {write("absurd.nii", absurd), "truncated"},
      {write("huge.nii", huge), "at most 2048"},  // refused from the header (exit 4), before reading
      {write("head.mgz", bytes), "FreeSurfer"},
      {write("negative.nii", negative), "dimension"},
      {write("text.nii", "this is not an image at all, only some text long enough to be read as a header\n"),
       "not a NIfTI"},
      {write("empty.nii", ""), "not a NIfTI"},
      {write("cut.nii.gz", gz_bytes.substr(0, gz_bytes.size() / 2)), "truncated"},
      {dir.file("missing.nii"), "no such file"},
  };
  for (const auto& [path, what] : cases) {
    std::filesystem::remove(dir.file("out.png"));
    auto r = voxview("--image '" + path + "'");
    // Sizes beyond the reader's limit are exit 4, whatever the file holds; the rest is malformed (3).
    EXPECT_EQ(r.exit_code, what == "at most 2048" || what == "FreeSurfer" ? 4 : 3) << path << ": " << r.output;
    EXPECT_NE(r.output.find(path), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(what), std::string::npos) << what << ": " << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.png"))) << path;
  }
}

}  // namespace
}  // namespace vxl
