// Export to TrackVis .trk (and .trk.gz): read back by our reader to float precision with every value set
// that fits the header's name slots, the header of a TRK source kept, a 1 mm RAS header covering the
// bounds otherwise; what TRK cannot hold is named in warnings. (scripts/check-trk-export compares with
// nibabel by hand.)
#include <bit>
#include <cfloat>
#include <cmath>
#include <filesystem>

#include "converter/convert/convert.h"
#include "converter/export/export_trk.h"
#include "converter/readers/read_tractogram.h"
#include "converter/synth/synth.h"
#include "format/vxl_file.h"
#include "tests/export_test_support.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::q;
using test::ScratchDir;

Tractogram valued_tractogram() {
  SynthSettings settings;
  settings.streamlines = 200;
  Tractogram t = synthesize_tractogram(settings);
  t.source.path = "valued.tck";
  t.source.format = "tck";
  const float one[3] = {1, 2, 3};
  t.add_streamline(one, 0);  // TRK cannot hold it
  const std::uint64_t n = t.point_count();
  std::vector<float> fa(n), r(n), g(n), b(n), length(t.streamline_count());
  for (std::uint64_t i = 0; i < n; ++i) {
    fa[i] = 0.001f * static_cast<float>(i);
    r[i] = float(i % 7), g[i] = float(i % 5), b[i] = -float(i % 3);
  }
  for (std::uint64_t s = 0; s < length.size(); ++s) length[s] = 1.5f * static_cast<float>(s);
  t.point_values = {{"fa", fa}, {"rgb[0]", r}, {"rgb[1]", g}, {"rgb[2]", b}};
  t.streamline_values = {{"length", length}};
  t.groups.push_back({"left", {0, 3}});
  return t;
}

// Same streamlines (the source's without its empty ones) to float precision: a point is stored in voxmm,
// measured from the grid's corner, so its rounding is that of the largest voxmm, which is at most twice
// the largest coordinate for the grids here.
void expect_close_streamlines(const Tractogram& source, const Tractogram& back) {
  float largest = 1;
  for (float v : source.positions) largest = std::max(largest, std::fabs(v));
  const float tolerance = 4 * FLT_EPSILON * 2 * largest;
  std::uint64_t i = 0;
  for (std::uint64_t s = 0; s < source.streamline_count(); ++s) {
    if (source.offsets[s] == source.offsets[s + 1]) continue;
    ASSERT_LT(i, back.streamline_count());
    ASSERT_EQ(back.offsets[i + 1] - back.offsets[i], source.offsets[s + 1] - source.offsets[s]) << s;
    for (std::uint64_t k = 0; k < 3 * (source.offsets[s + 1] - source.offsets[s]); ++k)
      ASSERT_NEAR(source.positions[3 * source.offsets[s] + k], back.positions[3 * back.offsets[i] + k], tolerance)
          << "streamline " << s;
    ++i;
  }
  EXPECT_EQ(i, back.streamline_count());
}

TEST(ExportTrk, ReadsBackWithItsValuesUnderADefaultRasHeader) {
  ScratchDir dir;
  const VxlFile f = VxlFile::open(test::convert_float32(valued_tractogram(), dir.file("v.vxl")));
  const TrkExportSummary s = export_trk(f, dir.file("v.trk"));
  EXPECT_EQ(s.streamlines, 200u);
  EXPECT_TRUE(test::has_warning(s.warnings, "1 streamline(s) without points not written"));
  EXPECT_TRUE(test::has_warning(s.warnings, "1 group(s) not written: a TRK has no place for them: 'left'"));
  ASSERT_EQ(test::run_cli("export " + q(dir.file("v.vxl")) + " " + q(dir.file("v.trk.gz"))).exit_code, 0);
  const Tractogram source = valued_tractogram();
  for (const char* name : {"v.trk", "v.trk.gz"}) {
    SCOPED_TRACE(name);
    const Tractogram back = read_trk(dir.file(name));
    expect_close_streamlines(source, back);
    EXPECT_EQ(back.source.header["voxel_order"], "RAS");
    EXPECT_EQ(back.source.header["voxel_size"], nlohmann::json({1.0, 1.0, 1.0}));
    EXPECT_TRUE(back.source.warnings.empty()) << ::testing::PrintToString(back.source.warnings);
    // The rgb run is one slot ("rgb\03"), read back as the same three sets.
    ASSERT_EQ(back.point_values.size(), 4u);
    for (std::size_t k = 0; k < 4; ++k) {
      EXPECT_EQ(back.point_values[k].name, source.point_values[k].name);
      // The empty streamline is the last: the values before it are all there is.
      EXPECT_EQ(back.point_values[k].values, source.point_values[k].values) << k;
    }
    ASSERT_EQ(back.streamline_values.size(), 1u);
    EXPECT_EQ(back.streamline_values[0].name, "length");
    EXPECT_EQ(back.streamline_values[0].values, std::vector<float>(source.streamline_values[0].values.begin(),
                                                                   source.streamline_values[0].values.end() - 1));
    // Every point lies in the grid the header describes (voxmm from 0 to dim * 1 mm).
    const auto dim = back.source.header["dim"];
    for (int c = 0; c < 3; ++c)
      EXPECT_GE(dim[c].get<double>(), f.meta().bounds_max[c] - std::floor(f.meta().bounds_min[c]));
  }
}

TEST(ExportTrk, KeepsTheHeaderOfATrkSource) {
  ScratchDir dir;
  Tractogram t = valued_tractogram();
  t.point_values.clear();
  t.streamline_values.clear();
  t.groups.clear();
  t.source.format = "trk";
  // LPS voxel order under a RAS-oriented vox_to_ras with 2 mm voxels: the reader re-orients, so the writer must too.
  t.source.header = {
      {"dim", {64, 80, 50}},
      {"voxel_size", {2.0, 2.0, 2.5}},
      {"origin", {0.0, 0.0, 0.0}},
      {"vox_to_ras", {{2.0, 0.0, 0.0, -64.0}, {0.0, 2.0, 0.0, -80.0}, {0.0, 0.0, 2.5, -60.0}, {0, 0, 0, 1}}},
      {"voxel_order", "LPS"},
      {"image_orientation_patient", {1.0, 0.0, 0.0, 0.0, 1.0, 0.0}},
      {"invert_x", 0},
      {"swap_xy", 1}};
  const VxlFile f = VxlFile::open(test::convert_float32(t, dir.file("t.vxl")));
  export_trk(f, dir.file("t.trk"));
  const Tractogram back = read_trk(dir.file("t.trk"));
  expect_close_streamlines(t, back);
  for (const char* key : {"dim", "voxel_size", "vox_to_ras", "voxel_order", "image_orientation_patient", "swap_xy"})
    EXPECT_EQ(back.source.header[key], t.source.header[key]) << key;
  EXPECT_TRUE(test::has_warning(back.source.warnings, "voxel_order LPS disagrees"));
}

// A TRK source's points come back bit for bit, even under an oblique affine: each RAS point was made from a stored
// point, and the export finds that stored point (the inverse affine's answer alone misses some by an ulp).
TEST(ExportTrk, ATrkSourceComesBackBitForBitUnderAnObliqueAffine) {
  ScratchDir dir;
  SynthSettings settings;
  settings.streamlines = 300;
  Tractogram t = synthesize_tractogram(settings);
  t.source.format = "trk";
  const double c = std::cos(0.12), s = std::sin(0.12);
  t.source.header = {
      {"dim", {64, 128, 160}},
      {"voxel_size", {4.0, 2.0, 1.0}},
      {"origin", {0.0, 0.0, 0.0}},
      {"vox_to_ras", {{4 * c, -2 * s, 0.0, -110.0}, {4 * s, 2 * c, 0.0, -120.0}, {0.0, 0.0, 1.0, -80.0}, {0, 0, 0, 1}}},
      {"voxel_order", "RAS"},
      {"image_orientation_patient", {1.0, 0.0, 0.0, 0.0, 1.0, 0.0}},
      {"invert_x", 0},
      {"swap_xy", 0}};
  export_trk(VxlFile::open(test::convert_float32(t, dir.file("first.vxl"))), dir.file("first.trk"));
  const Tractogram source = read_trk(dir.file("first.trk"));  // RAS points made from stored ones
  ASSERT_EQ(source.streamline_count(), 300u);
  export_trk(VxlFile::open(test::convert_float32(read_trk(dir.file("first.trk")), dir.file("second.vxl"))),
             dir.file("second.trk"));
  const Tractogram back = read_trk(dir.file("second.trk"));
  ASSERT_EQ(back.offsets, source.offsets);
  std::uint64_t differ = 0;
  for (std::size_t i = 0; i < source.positions.size(); ++i)
    differ += std::bit_cast<std::uint32_t>(back.positions[i]) != std::bit_cast<std::uint32_t>(source.positions[i]);
  EXPECT_EQ(differ, 0u) << "of " << source.positions.size() << " coordinates";
}

TEST(ExportTrk, SetsBeyondTheNameSlotsAreNamedInAWarning) {
  ScratchDir dir;
  Tractogram t = valued_tractogram();
  t.point_values.resize(1);
  for (int k = 0; k < 10; ++k) t.point_values.push_back({"s" + std::to_string(k), t.point_values[0].values});
  t.point_values.push_back({"a_name_of_twenty_one_", t.point_values[0].values});
  const VxlFile f = VxlFile::open(test::convert_float32(std::move(t), dir.file("t.vxl")));
  const TrkExportSummary s = export_trk(f, dir.file("t.trk"));
  EXPECT_TRUE(test::has_warning(s.warnings, "per-point value set(s) not written: 's9', 'a_name_of_twenty_one_' (name)"))
      << ::testing::PrintToString(s.warnings);
  const Tractogram back = read_trk(dir.file("t.trk"));
  ASSERT_EQ(back.point_values.size(), 10u);
  EXPECT_EQ(back.point_values[9].name, "s8");
  EXPECT_TRUE(back.source.warnings.empty()) << ::testing::PrintToString(back.source.warnings);
}

TEST(ExportTrk, OneGroupThroughTheCommandLine) {
  ScratchDir dir;
  test::convert_float32(valued_tractogram(), dir.file("v.vxl"));
  const auto r = test::run_cli("export " + q(dir.file("v.vxl")) + " " + q(dir.file("left.TRK")) + " --group left");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 streamlines"), std::string::npos) << r.output;
  const Tractogram back = read_trk(dir.file("left.TRK"));
  ASSERT_EQ(back.streamline_count(), 2u);
  EXPECT_EQ(back.streamline_values[0].values, (std::vector<float>{0.0f, 4.5f})) << "streamlines 0 and 3";
}

TEST(ExportTrkReal, TrkFixturesComeBackWithTheirHeaders) {
  VXL_REQUIRE_REAL_DATA();
  ScratchDir dir;
  for (const char* name : {"nibabel__complex.trk", "nibabel__standard.LPS.trk", "niivue__colby.trk"}) {
    SCOPED_TRACE(name);
    const Tractogram source = read_trk(test::real(name));
    const VxlFile f = VxlFile::open(test::convert_float32(read_trk(test::real(name)), dir.file("r.vxl")));
    export_trk(f, dir.file("r.trk.gz"));
    const Tractogram back = read_trk(dir.file("r.trk.gz"));
    expect_close_streamlines(source, back);
    for (const char* key : {"dim", "voxel_size", "vox_to_ras", "voxel_order", "voxmm_to_rasmm"})
      EXPECT_EQ(back.source.header[key], source.source.header[key]) << key;
    ASSERT_EQ(back.point_values.size(), source.point_values.size());
    for (std::size_t k = 0; k < source.point_values.size(); ++k) {
      EXPECT_EQ(back.point_values[k].name, source.point_values[k].name);
      EXPECT_EQ(back.point_values[k].values, source.point_values[k].values);
    }
    ASSERT_EQ(back.streamline_values.size(), source.streamline_values.size());
    for (std::size_t k = 0; k < source.streamline_values.size(); ++k)
      EXPECT_EQ(back.streamline_values[k].values, source.streamline_values[k].values);
  }
}

}  // namespace
}  // namespace vxl
