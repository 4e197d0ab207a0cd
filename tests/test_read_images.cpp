// Images in every format read_volume_image takes must give the same voxels in the same place: MRtrix
// images (tests/mif_test_files.h) against the NIfTI image they equal, whatever their storage layout; and
// the formats it does not read are refused naming them.
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "converter/readers/volume_image.h"
#include "format/base/error.h"
#include "tests/hostile_inputs.h"
#include "tests/mif_test_files.h"
#include "tests/nifti_test_files.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::MifSpec;
using test::ScratchDir;
namespace hostile = test::hostile;

// 4 x 3 x 2 voxels, each holding its own index; the sform maps i to -y (2 mm), j to +x (3 mm), k to +z
// (4 mm), from (10, -20, 30).
constexpr std::array<std::int64_t, 3> kDims{4, 3, 2};
const std::array<double, 12> kSform{0, 3, 0, 10, -2, 0, 0, -20, 0, 0, 4, 30};

std::vector<double> indices(std::size_t n) {
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = double(i);
  return v;
}

// The .mif equal to the NIfTI: the rigid part of the sform and its column lengths as vox.
MifSpec equivalent(std::vector<int> layout) {
  MifSpec s;
  s.dims = {kDims[0], kDims[1], kDims[2]};
  s.vox = {2, 3, 4};
  s.layout = std::move(layout);
  s.transform = {0, 1, 0, 10, -1, 0, 0, -20, 0, 0, 1, 30};
  return s;
}

Error error_of(const std::string& path) {
  try {
    (void)read_volume_image(path);
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << path << ": no error";
  return Error(ErrorKind::Usage, "", std::nullopt, "no error");
}

void expect_same(const VolumeImage& a, const VolumeImage& b) {
  EXPECT_EQ(a.dims, b.dims);
  EXPECT_EQ(a.values, b.values);
  for (int i = 0; i < 16; ++i) EXPECT_NEAR(a.voxel_to_ras[i], b.voxel_to_ras[i], 1e-9) << i;
}

TEST(MrtrixImage, EveryLayoutReadsAsTheEquivalentNifti) {
  ScratchDir dir;
  std::vector<std::int16_t> v(24);
  for (int i = 0; i < 24; ++i) v[i] = std::int16_t(i);
  test::write_nifti_int16(dir.file("ref.nii"), kDims, v, kSform);
  const VolumeImage ref = read_volume_image(dir.file("ref.nii"));
  for (const std::vector<int>& layout : {std::vector<int>{1, 2, 3}, {-1, 2, 3}, {3, -1, 2}, {-3, -2, -1}}) {
    SCOPED_TRACE(test::mif_list({layout[0], layout[1], layout[2]}));
    const MifSpec spec = equivalent(layout);
    const std::string bytes = test::mif_bytes(spec, indices(24));
    hostile::write_file(dir.file("a.mif"), bytes);
    expect_same(read_volume_image(dir.file("a.mif")), ref);
    hostile::write_file(dir.file("a.mif.gz"), hostile::gzip(bytes));
    expect_same(read_volume_image(dir.file("a.mif.gz")), ref);
    hostile::write_file(dir.file("a data.dat"), test::mif_data(spec, indices(24)));
    for (bool end_line : {false, true}) {
      hostile::write_file(dir.file("a.mih"), test::mih_header(spec, "a data.dat", end_line));
      expect_same(read_volume_image(dir.file("a.mih")), ref);
    }
  }
}

// A 4D image stored volume-fastest (as MRtrix stores DWI): its first volume, scaled.
TEST(MrtrixImage, FourDimensionsGiveTheFirstVolumeScaled) {
  ScratchDir dir;
  MifSpec spec = equivalent({2, 3, 4, 1});
  spec.dims.push_back(5);
  spec.vox.push_back(1);
  spec.datatype = "Float32LE";
  spec.extra = "scaling: 1,0.5\n";
  std::vector<double> values(24 * 5);
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = i < 24 ? double(i) : -7.0;
  hostile::write_file(dir.file("dwi.mif"), test::mif_bytes(spec, values));
  const VolumeImage img = read_volume_image(dir.file("dwi.mif"));
  ASSERT_EQ(img.values.size(), 24u);
  for (int i = 0; i < 24; ++i) EXPECT_EQ(img.values[i], 1.0f + 0.5f * float(i)) << i;
}

TEST(MrtrixImage, DamagedOrUnsupportedHeadersAreRefusedNamingTheFile) {
  ScratchDir dir;
  const MifSpec good = equivalent({1, 2, 3});
  const std::string bytes = test::mif_bytes(good, indices(24));
  MifSpec bit = good;
  bit.datatype = "Bit";
  MifSpec flat = good;
  flat.transform = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0};
  MifSpec bad_layout = good;
  bad_layout.layout = {1, 1, 3};
  MifSpec negative_vox = good;
  negative_vox.vox[0] = -1;
  std::string no_layout = bytes;  // "layout:" renamed, one letter changed: the data offset holds
  const std::size_t layout_at = no_layout.find("layout:");
  ASSERT_NE(layout_at, std::string::npos);
  no_layout[layout_at + 5] = 'x';
  MifSpec scientific_dim = good;  // a later 'dim:' line, the same sizes in another notation
  scientific_dim.extra = "dim: " + std::to_string(good.dims[0]) + "e0," + std::to_string(good.dims[1]) + "," +
                         std::to_string(good.dims[2]) + "\n";
  struct Case {
    std::string name, bytes;
    ErrorKind kind;
    std::string says;
  };
  const Case cases[] = {
      {"bit.mif", test::mif_bytes(bit, indices(24)), ErrorKind::Unsupported, "datatype Bit"},
      {"flat.mif", test::mif_bytes(flat, indices(24)), ErrorKind::Input, "voxel axis 2 0 mm long"},
      {"layout.mif", test::mif_bytes(bad_layout, indices(24)), ErrorKind::Input, "layout"},
      {"negative-vox.mif", test::mif_bytes(negative_vox, indices(24)), ErrorKind::Input,
       "'vox: -1.000000,3.000000,4.000000': expected positive voxel sizes"},
      {"no-layout.mif", no_layout, ErrorKind::Input, "lacks 'layout:'"},
      {"scientific-dim.mif", test::mif_bytes(scientific_dim, indices(24)), ErrorKind::Input,
       "expected whole numbers 1 to 2^31, in digits"},
      {"gzip-named.nii", hostile::gzip(test::nifti1_bytes({2, 2, 2}, 2, 8, std::string(8, '\1'))), ErrorKind::Input,
       "holds gzip-compressed data but is not named .gz"},
      {"cut.mif", bytes.substr(0, bytes.size() - 10), ErrorKind::Input, "truncated MRtrix image data"},
      {"noend.mif", bytes.substr(0, bytes.find("END")), ErrorKind::Input, "no 'END' line"},
      {"cut.mif.gz", hostile::gzip(bytes, /*finish=*/false), ErrorKind::Input, "end-of-stream marker"},
      {"junk.mif.gz", hostile::gzip(bytes) + "junk", ErrorKind::Input, "not another gzip member"},
      {"nifti.mif", test::nifti1_bytes({2, 2, 2}, 2, 8, std::string(8, '\0')), ErrorKind::Input, "mrtrix image"},
      {"head.mgz", bytes, ErrorKind::Unsupported, ".mgz (FreeSurfer MGZ) is not supported"},
      {"head.nrrd", bytes, ErrorKind::Unsupported, "(NRRD) is not supported"},
      {"head.hdr", bytes, ErrorKind::Unsupported, "two-file NIfTI"},
  };
  for (const Case& c : cases) {
    const std::string p = dir.file(c.name);
    hostile::write_file(p, c.bytes);
    const Error e = error_of(p);
    EXPECT_EQ(e.kind(), c.kind) << c.name << ": " << e.what();
    EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << c.says << ": " << e.what();
  }
  hostile::write_file(dir.file("lost.mih"), test::mih_header(good, "missing.dat"));
  EXPECT_NE(std::string(error_of(dir.file("lost.mih")).what()).find("missing.dat"), std::string::npos);
  // A negative offset after an existing data file is a bad offset, not a file named "good.dat -5".
  hostile::write_file(dir.file("good.dat"), std::string(24, '\0'));
  hostile::write_file(dir.file("negative.mih"), test::mih_header(good, "good.dat -5"));
  const Error negative = error_of(dir.file("negative.mih"));
  EXPECT_EQ(negative.kind(), ErrorKind::Input) << negative.what();
  EXPECT_NE(std::string(negative.what()).find("bad offset: '-5'"), std::string::npos) << negative.what();
}

// A bomb in .mif.gz form: refused from the header as a .nii.gz is.
TEST(MrtrixImage, GzipBombIsRefusedFromItsHeader) {
  ScratchDir dir;
  MifSpec spec = equivalent({1, 2, 3});
  spec.dims = {512, 512, 512};
  spec.datatype = "UInt8";
  std::string head = test::mif_bytes(spec, {});
  head.resize(head.find("END\n") + 4 + 16);  // the header and its padding, no data
  std::string gz = hostile::gzip(head);
  const std::string zeros = hostile::gzip(std::string(1u << 20, '\0'));
  for (int i = 0; i < 128; ++i) gz += zeros;
  hostile::write_file(dir.file("bomb.mif.gz"), gz);
  const Error e = error_of(dir.file("bomb.mif.gz"));
  EXPECT_EQ(e.kind(), ErrorKind::Unsupported) << e.what();
  EXPECT_NE(std::string(e.what()).find("decompression bomb"), std::string::npos) << e.what();
}

// The same mask as .nii.gz and as .mif selects the same streamlines.
TEST(MrtrixImage, SelectTakesAMifMask) {
  ScratchDir dir;
  test::run_cli("synth " + test::q(dir.file("in.tck")) + " --streamlines 200 --seed 3");
  test::run_cli("convert " + test::q(dir.file("in.tck")) + " " + test::q(dir.file("in.vxl")));
  ASSERT_TRUE(std::filesystem::exists(dir.file("in.vxl")));
  std::vector<std::int16_t> v(20 * 20 * 20, 0);
  for (int k = 5; k < 15; ++k)
    for (int j = 5; j < 15; ++j)
      for (int i = 5; i < 15; ++i) v[std::size_t(i + 20 * (j + 20 * k))] = 1;
  const std::array<double, 12> affine{-4, 0, 0, 40, 0, 4, 0, -40, 0, 0, 4, -40};
  test::write_nifti_int16(dir.file("mask.nii.gz"), {20, 20, 20}, v, affine);
  MifSpec spec;
  spec.dims = {20, 20, 20};
  spec.vox = {4, 4, 4};
  spec.layout = {-1, 2, 3};
  spec.transform = {-1, 0, 0, 40, 0, 1, 0, -40, 0, 0, 1, -40};
  hostile::write_file(dir.file("mask.mif"), test::mif_bytes(spec, std::vector<double>(v.begin(), v.end())));
  const auto nii =
      test::run_cli("select " + test::q(dir.file("in.vxl")) + " --count --include " + test::q(dir.file("mask.nii.gz")));
  const auto mif =
      test::run_cli("select " + test::q(dir.file("in.vxl")) + " --count --include " + test::q(dir.file("mask.mif")));
  ASSERT_EQ(nii.exit_code, 0) << nii.output;
  EXPECT_EQ(mif.exit_code, 0) << mif.output;
  EXPECT_EQ(mif.output, nii.output);
  EXPECT_NE(nii.output.find_first_of("123456789"), std::string::npos) << "the mask must select some: " << nii.output;
}

}  // namespace
}  // namespace vxl
