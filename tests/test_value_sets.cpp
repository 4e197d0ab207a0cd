// Values besides positions: the TSF reader, TRK scalars and properties, TRX dpv and dps, and their way into
// the .vxl (VVAL / SVAL, spec §5.11): per-point values spread over the vertices like the positions
// (interpolated at synthetic face points, copied at connecting vertices), per-streamline values as they are.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

#include "converter/convert/convert.h"
#include "converter/convert/streaming_convert.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/read_tsf.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_positions.h"
#include "format/vxl_streamlines.h"
#include "format/vxl_verify.h"
#include "tests/mrtrix_test_files.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::raw;
using test::real;
using test::ScratchDir;

// A TSF with the given datatype and raw data bytes (header padded so that the offset has 4 digits).
void write_tsf(const std::string& path, const std::string& datatype, const std::string& data,
               const std::string& extra = "") {
  test::write_mrtrix_file(path, "mrtrix track scalars", datatype, data, extra);
}

const float kNaN = NAN, kInf = INFINITY;

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

// Two streamlines of 3 and 2 points.
Tractogram five_points() {
  Tractogram t;
  const float a[] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  const float b[] = {0, 5, 0, 0, 6, 0};
  t.add_streamline(a, 3);
  t.add_streamline(b, 2);
  t.source.path = "five.tck";
  return t;
}

TEST(TsfReader, ReadsValuesPerStreamlineInEveryDatatype) {
  ScratchDir dir;
  write_tsf(dir.file("a.tsf"), "Float32LE", raw<float>({1, 2, 3, kNaN, 4, 5, kNaN, kInf}));
  TrackScalars a = read_tsf(dir.file("a.tsf"));
  EXPECT_EQ(a.values, (std::vector<float>{1, 2, 3, 4, 5}));
  EXPECT_EQ(a.offsets, (std::vector<std::uint64_t>{0, 3, 5}));
  EXPECT_TRUE(a.warnings.empty());

  write_tsf(dir.file("b.tsf"), "Float64BE", raw<double>({0.25, kNaN, -1.5, 2.5, kNaN}, true), "timestamp: 12.5\n");
  TrackScalars b = read_tsf(dir.file("b.tsf"));
  EXPECT_EQ(b.values, (std::vector<float>{0.25f, -1.5f, 2.5f}));
  EXPECT_EQ(b.offsets, (std::vector<std::uint64_t>{0, 1, 3}));
  EXPECT_EQ(b.timestamp, "12.5");
  EXPECT_TRUE(b.warnings.empty()) << "ending on a streamline's NaN without Inf is what real files do";

  write_tsf(dir.file("c.tsf"), "Float32LE", raw<float>({7, 8}));
  TrackScalars c = read_tsf(dir.file("c.tsf"));
  EXPECT_EQ(c.offsets, (std::vector<std::uint64_t>{0, 2}));
  EXPECT_EQ(c.warnings.size(), 1u);

  write_tsf(dir.file("d.tsf"), "Int16LE", raw<float>({1, kInf}));
  EXPECT_NE(error_of([&] { read_tsf(dir.file("d.tsf")); }).find("Int16LE"), std::string::npos);
  std::ofstream(dir.file("e.tsf")) << "mrtrix tracks\ndatatype: Float32LE\nfile: . 50\nEND\n";
  EXPECT_NE(error_of([&] { read_tsf(dir.file("e.tsf")); }).find("mrtrix track scalars"), std::string::npos);
}

TEST(TsfReader, AttachRefusesAFileThatDoesNotMatchPointForPoint) {
  ScratchDir dir;
  write_tsf(dir.file("good.tsf"), "Float32LE", raw<float>({1, 2, 3, kNaN, 4, 5, kNaN, kInf}));
  Tractogram t = five_points();
  attach_tsf(t, dir.file("good.tsf"));
  ASSERT_EQ(t.point_values.size(), 1u);
  EXPECT_EQ(t.point_values[0].name, "good");
  EXPECT_EQ(t.point_values[0].values, (std::vector<float>{1, 2, 3, 4, 5}));
  ASSERT_EQ(t.source.value_files.size(), 1u);
  EXPECT_EQ(t.source.value_files[0]["name"], "good.tsf");

  write_tsf(dir.file("fewer.tsf"), "Float32LE", raw<float>({1, 2, 3, kNaN, kInf}));
  const std::string fewer = error_of([&] {
    Tractogram u = five_points();
    attach_tsf(u, dir.file("fewer.tsf"));
  });
  EXPECT_NE(fewer.find("fewer.tsf"), std::string::npos) << fewer;
  EXPECT_NE(fewer.find("1 streamlines and 3 values"), std::string::npos) << fewer;
  EXPECT_NE(fewer.find("2 streamlines and 5 points"), std::string::npos) << fewer;

  // The same totals, split differently.
  write_tsf(dir.file("shifted.tsf"), "Float32LE", raw<float>({1, 2, kNaN, 3, 4, 5, kNaN, kInf}));
  const std::string shifted = error_of([&] {
    Tractogram u = five_points();
    attach_tsf(u, dir.file("shifted.tsf"));
  });
  EXPECT_NE(shifted.find("shifted.tsf"), std::string::npos) << shifted;
  EXPECT_NE(shifted.find("streamline 0 has 2 values but 3 points"), std::string::npos) << shifted;
}

// Per source point, the values a .vxl holds, walked like export walks positions: synthetic points and
// connecting vertices are left out.
// The per-point values of set `set` in source order (synthetic points left out), by the walk of spec §5.6.
std::vector<float> point_values_of(const VxlFile& f, std::uint32_t set) {
  std::vector<float> out;
  const auto values = f.vertex_values().values(set);
  WalkCallbacks cb;
  cb.voxline = [&](const VoxlineVisit& v) {
    out.insert(out.end(), values.begin() + v.first_vertex, values.begin() + v.first_vertex + v.own_points);
  };
  walk_streamlines(f, cb);
  // The walk reports synthetic first points too; drop them by the voxline table's flags.
  std::vector<float> source;
  std::size_t at = 0;
  for (const VoxlineEntry& e : f.voxlines()) {
    const std::uint32_t own = e.count_flags & kVoxlineCountMask;
    const std::uint32_t skip = (e.count_flags & kVoxlineSyntheticFirst) ? 1 : 0;
    source.insert(source.end(), out.begin() + at + skip, out.begin() + at + own);
    at += own;
  }
  return source;
}

TEST(ValueSets, PointValuesFollowTheirPointsIntoTheVertexBlocks) {
  ScratchDir dir;
  // One long step across many 2 mm voxels (split at every face), then short steps.
  Tractogram t;
  const float p[] = {0, 0, 0, 15, 0, 0, 15.5f, 0.5f, 0, 16, 1, 0};
  t.add_streamline(p, 4);
  const float q[] = {3, 3, 3, 3.5f, 3, 3};
  t.add_streamline(q, 2);
  t.point_values.push_back({"along", {0, 15, 15.5f, 16, -1, kNaN}});
  t.point_values.push_back({"constant", {2, 2, 2, 2, 2, 2}});
  t.streamline_values.push_back({"length", {16.5f, 0.5f}});
  ConvertSettings settings;
  settings.voxel_size = 2;
  settings.positions = PositionEncoding::Float32;  // the values are checked against exact positions
  settings.levels = 1;                             // one level: major version 1
  convert_tractogram(std::move(t), dir.file("v.vxl"), settings);
  VerifyResult verified = verify_vxl(dir.file("v.vxl"));
  ASSERT_TRUE(verified.valid) << verified.problem;

  VxlFile f = VxlFile::open(dir.file("v.vxl"));
  EXPECT_EQ(f.header().version_minor, 5);  // 1.5: streamline lengths (spec §10)
  EXPECT_GT(f.meta().synthetic_point_count, 5u);
  const ValueSets& vv = f.vertex_values();
  ASSERT_EQ(vv.size(), 2u);
  EXPECT_EQ(vv.name(0), "along");
  EXPECT_EQ(vv.find("constant"), 1);
  EXPECT_EQ(vv.min(0), -1.0f);  // the NaN is left out of the extremes
  EXPECT_EQ(vv.max(0), 16.0f);
  EXPECT_EQ(vv.min(1), 2.0f);
  EXPECT_EQ(vv.max(1), 2.0f);
  // Back per point, the source values exactly (the NaN bit for bit).
  const std::vector<float> back = point_values_of(f, 0);
  ASSERT_EQ(back.size(), 6u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(back[i], (std::vector<float>{0, 15, 15.5f, 16, -1})[i]);
  EXPECT_TRUE(std::isnan(back[5]));
  // The value "along" equals x on the first streamline: every vertex there, synthetic or connecting,
  // carries its own x.
  const auto positions = f.float_vertices();
  const auto along = vv.values(0), constant = vv.values(1);
  int checked = 0;
  for (std::uint64_t i = 0; i < f.meta().vertex_count; ++i) {
    EXPECT_EQ(constant[i], 2.0f);
    if (positions[3 * i + 2] == 0.0f) {  // first streamline (z = 0)
      EXPECT_NEAR(along[i], positions[3 * i], 1e-5) << "vertex " << i;
      ++checked;
    }
  }
  EXPECT_GT(checked, 12);
  const ValueSets& sv = f.streamline_values();
  ASSERT_EQ(sv.size(), 1u);
  EXPECT_EQ(sv.name(0), "length");
  EXPECT_EQ(std::vector<float>(sv.values(0).begin(), sv.values(0).end()), (std::vector<float>{16.5f, 0.5f}));

  // Without values: no value sections, the same version.
  ConvertSettings exact;
  exact.positions = PositionEncoding::Float32;
  exact.levels = 1;
  convert_tractogram(five_points(), dir.file("plain.vxl"), exact);
  VxlFile plain = VxlFile::open(dir.file("plain.vxl"));
  EXPECT_EQ(plain.header().version_minor, 5);
  EXPECT_TRUE(plain.vertex_values().empty());
  EXPECT_EQ(plain.find_section(section_id("VVAL")), nullptr);
}

// A source read whole goes through the passes of any conversion: its per-point values placed range by range (and,
// written block by block, beside blocks that are read back), its per-streamline values and groups written at the end,
// the same bytes under every limit. "x" is each point's x, so every vertex (added on a face or connecting) carries
// its own x wherever it was placed.
TEST(ValueSets, ASourceReadWholeWritesItsValuesAlikeUnderEveryLimit) {
  ScratchDir dir;
  Tractogram t;
  std::vector<float> x, index;
  for (int s = 0; s < 3000; ++s) {
    std::vector<float> pts;
    for (int i = 0; i < 12; ++i) {  // 5 mm along z over 4 mm voxels: points added on faces
      const float a = 0.25f * i + 0.37f * s;
      pts.insert(pts.end(), {12 * std::cos(a) + float(s % 11), 12 * std::sin(a), 5.0f * i - 0.01f * s});
      x.push_back(pts[pts.size() - 3]);
      index.push_back(float(x.size()));
    }
    t.add_streamline(pts.data(), 12);
  }
  t.point_values.push_back({"x", x});
  t.point_values.push_back({"index", index});
  std::vector<float> per_streamline(t.streamline_count());
  for (std::size_t k = 0; k < per_streamline.size(); ++k) per_streamline[k] = float(k % 7);
  t.streamline_values.push_back({"k", per_streamline});
  t.groups.push_back({"odd", {1, 3, 5, 2999}});
  // Packed positions are placed in two halves of the voxels side by side; float32 ones in one.
  for (const PositionEncoding encoding : {PositionEncoding::Float32, PositionEncoding::Packed}) {
    SCOPED_TRACE(position_encoding_name(encoding));
    ConvertSettings settings;
    settings.voxel_size = 4;
    settings.positions = encoding;
    settings.threads = 2;
    convert_tractogram(Tractogram(t), dir.file("default.vxl"), settings);
    const std::vector<char> expected = test::slurp(dir.file("default.vxl"));

    // Several ranges of voxels, one pass each: about half a MiB of a range is taken before its voxels, so 640 KiB
    // gives 13 (float32) and 5 (packed) ranges, and anything under that one a voxel (a thousand passes).
    StreamingTuning ranges;
    ranges.range_bytes = 640 << 10;
    settings.memory_limit = 64ull << 20;
    const ConvertSummary cut = convert_streaming(t, dir.file("ranges.vxl"), settings, ranges);
    EXPECT_GT(cut.partitions, 2u);
    EXPECT_TRUE(test::slurp(dir.file("ranges.vxl")) == expected);

    StreamingTuning blocks;  // written block by block and read back
    blocks.vertex_blocks = true;
    settings.memory_limit = 512ull << 20;
    const ConvertSummary read_back = convert_streaming(t, dir.file("blocks.vxl"), settings, blocks);
    EXPECT_TRUE(read_back.vertices_read_back);
    EXPECT_TRUE(test::slurp(dir.file("blocks.vxl")) == expected);

    const VxlFile f = VxlFile::open(dir.file("default.vxl"));
    EXPECT_GT(f.meta().synthetic_point_count, 1000u);
    const auto along = f.vertex_values().values(0);
    std::vector<float> xyz;
    for (const VoxelEntry& v : f.voxels()) {  // every vertex carries its own x (packed: within the bound)
      xyz.resize(3 * std::size_t(v.vertex_count));
      if (encoding == PositionEncoding::Packed)
        unpack_block(v, f.packed_vertices().data() + v.vertex_first, v.vertex_count, xyz.data());
      else
        std::copy_n(f.float_vertices().data() + 3 * v.vertex_first, xyz.size(), xyz.data());
      for (std::uint32_t e = 0; e < v.vertex_count; ++e)
        ASSERT_NEAR(along[v.vertex_first + e], xyz[3 * e], 0.01) << "vertex " << v.vertex_first + e;
    }
    EXPECT_EQ(f.streamline_values().size(), 1u);
    ASSERT_EQ(f.groups().size(), 1u);
    EXPECT_EQ(f.groups()[0].members, (std::vector<std::uint64_t>{1, 3, 5, 2999}));
  }
}

// Beyond 64 value sets the rest are dropped, and a warning on stderr says so.
TEST(ValueSets, SetsBeyondTheCapAreDroppedWithAWarningOnStderr) {
  ScratchDir dir;
  std::string vtk =
      "# vtk DataFile Version 3.0\nsets\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n0 0 0 1 1 1\n"
      "LINES 1 3\n2 0 1\nPOINT_DATA 2\n";
  for (int k = 0; k < 65; ++k) vtk += "SCALARS s" + std::to_string(k) + " float 1\nLOOKUP_TABLE default\n1 2\n";
  const std::string in = dir.file("sets.vtk"), out = dir.file("sets.vxl");
  std::ofstream(in) << vtk;
  const auto r = test::run_cli("convert " + test::q(in) + " " + test::q(out));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: " + in + ": only the first 64 of 65 per-point value sets are kept"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(VxlFile::open(out).vertex_values().size(), 64u);
}

TEST(ValueSets, OpenRefusesAMalformedSection) {
  ScratchDir dir;
  Tractogram t = five_points();
  t.point_values.push_back({"v", {1, 2, 3, 4, 5}});
  convert_tractogram(std::move(t), dir.file("v.vxl"), {});
  std::string bytes = test::slurp<std::string>(dir.file("v.vxl"));
  VxlFile f = VxlFile::open(dir.file("v.vxl"));
  const std::uint64_t at = f.find_section(section_id("VVAL"))->offset;
  auto patched = [&](std::uint64_t offset, std::uint32_t value) {
    std::string b = bytes;
    std::memcpy(b.data() + offset, &value, 4);
    std::ofstream(dir.file("bad.vxl"), std::ios::binary) << b;
    return error_of([&] { VxlFile::open(dir.file("bad.vxl")); });
  };
  EXPECT_NE(patched(at, 0).find("value-set count"), std::string::npos);
  EXPECT_NE(patched(at, 2).find("does not match"), std::string::npos);
  EXPECT_NE(patched(at + 8, 7).find("values per set"), std::string::npos);
  // A name without its NUL: 48 non-zero bytes.
  std::string b = bytes;
  std::memset(b.data() + at + 16, 'a', 48);
  std::ofstream(dir.file("bad.vxl"), std::ios::binary) << b;
  EXPECT_NE(error_of([&] { VxlFile::open(dir.file("bad.vxl")); }).find("NUL"), std::string::npos);
  // Long names are cut at a character boundary.
  EXPECT_EQ(value_set_name(std::string(46, 'x') + "\xc3\xa9\xc3\xa9").size(), 46u);
}

TEST(ValueSetsReal, TsfFixturesConvertWithTheirTractograms) {
  VXL_REQUIRE_REAL_DATA();
  ScratchDir dir;
  struct Case {
    const char *tck, *tsf;
    std::size_t points;
  } cases[] = {{"niivue__tract.SLF1_R.tck", "niivue__mni152.SLF1_R.tsf", 156},
               {"test_data__tracks.tck", "test_data__afd.tsf", 3408},
               {"test_data__tracks.tck", "test_data__tcksample__out.tsf", 3408}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.tsf);
    const std::string out = dir.file("out.vxl");
    auto r = test::run_cli("convert '" + real(c.tck) + "' '" + out + "' --tsf '" + real(c.tsf) + "'");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
    VerifyResult v = verify_vxl(out);
    ASSERT_TRUE(v.valid) << v.problem;
    VxlFile f = VxlFile::open(out);
    ASSERT_EQ(f.vertex_values().size(), 1u);
    TrackScalars tsf = read_tsf(real(c.tsf));
    ASSERT_EQ(tsf.values.size(), c.points);
    EXPECT_EQ(point_values_of(f, 0), tsf.values);
    EXPECT_NE(f.provenance_json().find(c.tsf), std::string::npos) << "provenance names the TSF";
  }
  // A TSF made for another tractogram is refused, naming it.
  auto wrong = test::run_cli("convert '" + real("niivue__tract.SLF1_R.tck") + "' '" + dir.file("wrong.vxl") +
                             "' --tsf '" + real("test_data__afd.tsf") + "'");
  EXPECT_EQ(wrong.exit_code, 3);
  EXPECT_NE(wrong.output.find("test_data__afd.tsf"), std::string::npos) << wrong.output;
  EXPECT_NE(wrong.output.find("500 streamlines and 3408 values"), std::string::npos) << wrong.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("wrong.vxl")));
}

TEST(ValueSetsReal, TrkScalarsAndPropertiesTrxDpvAndDps) {
  VXL_REQUIRE_REAL_DATA();
  // nibabel's complex.trk: per point colors (3) and fa, per streamline mean_colors (3), mean_curvature,
  // mean_torsion.
  Tractogram trk = read_tractogram(real("nibabel__complex.trk"));
  std::vector<std::string> point_names, streamline_names;
  for (const ValueSet& v : trk.point_values) {
    point_names.push_back(v.name);
    EXPECT_EQ(v.values.size(), trk.point_count());
  }
  for (const ValueSet& v : trk.streamline_values) {
    streamline_names.push_back(v.name);
    EXPECT_EQ(v.values.size(), trk.streamline_count());
  }
  EXPECT_EQ(point_names, (std::vector<std::string>{"colors[0]", "colors[1]", "colors[2]", "fa"}));
  EXPECT_EQ(streamline_names, (std::vector<std::string>{"mean_colors[0]", "mean_colors[1]", "mean_colors[2]",
                                                        "mean_curvature", "mean_torsion"}));
  // nibabel's test data: fa of the first streamline's point is 0.2, mean_curvature 1.11, 2.11, 3.11.
  EXPECT_FLOAT_EQ(trk.point_values[3].values[0], 0.2f);
  EXPECT_FLOAT_EQ(trk.streamline_values[3].values[0], 1.11f);
  EXPECT_FLOAT_EQ(trk.streamline_values[3].values[2], 3.11f);
  EXPECT_FLOAT_EQ(trk.streamline_values[4].values[1], 2.22f);

  Tractogram trx = read_tractogram(real("niivue__dpsv.trx"));
  ASSERT_EQ(trx.point_values.size(), 1u);
  EXPECT_EQ(trx.point_values[0].name, "z");
  ASSERT_EQ(trx.point_values[0].values.size(), trx.point_count());
  // dpv "z" of this file is each point's z coordinate (float16 positions, float32 values).
  for (std::uint64_t i = 0; i < trx.point_count(); i += 997)
    EXPECT_NEAR(trx.point_values[0].values[i], trx.positions[3 * i + 2], 0.05);
  ASSERT_EQ(trx.streamline_values.size(), 1u);
  EXPECT_EQ(trx.streamline_values[0].name, "DataSetID");
  EXPECT_EQ(trx.streamline_values[0].values.size(), trx.streamline_count());

  Tractogram gs = read_tractogram(real("trx-javascript__gs.trx"));
  std::vector<std::string> gs_names;
  for (const ValueSet& v : gs.streamline_values) gs_names.push_back(v.name);
  EXPECT_EQ(gs_names, (std::vector<std::string>{"random_coord[0]", "random_coord[1]", "random_coord[2]"}));
  EXPECT_EQ(gs.point_values.size(), 3u);
}

}  // namespace
}  // namespace vxl
