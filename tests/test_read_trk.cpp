// Tests of the TRK reader: every real TRK / TRK.GZ fixture (counts, reference points from nibabel,
// pairs that must agree) and small synthetic files, valid and broken, written to a scratch directory.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "converter/readers/read_tractogram.h"
#include "format/base/error.h"
#include "tests/test_support.h"

namespace {

using vxl::test::has_warning;
using vxl::test::real;

struct Counts {
  const char* file;
  std::uint64_t streamlines;
  std::uint64_t points;
};

// Streamline and point counts of the real fixtures, as their upstream projects publish them.
const Counts kTrkFixtures[] = {
    {"TractographyFormat__stroke.trk", 36763, 237468},
    {"TractographyFormat__example.trk", 305, 44249},
    {"niivue__stroke.trk.gz", 36763, 237468},
    {"niivue__C_PHP.trk.gz", 460, 95865},
    {"niivue__tract.IFOF_R.trk", 14, 168},
    {"niivue__colby.trk", 2, 32},
    {"dipy__tracks300.trk", 300, 14576},
    {"dipy__fbc34ca__tracks300.trk", 300, 14576},
    {"dipy__EuDX_small_25.trk", 60, 228},
    {"nibabel__empty.trk", 0, 0},
    {"nibabel__simple.trk", 3, 8},
    {"nibabel__complex.trk", 3, 8},
    {"nibabel__complex_big_endian.trk", 3, 8},
    {"nibabel__standard.trk", 120, 360},
    {"nibabel__standard.LPS.trk", 120, 360},
    {"trx-javascript__gs.trk", 13, 104},
    {"scilpy__reconstruction_metrics.trk", 31262, 62524},
    {"scilpy__tracking.trk", 15, 35782},
};

std::array<float, 3> point(const vxl::Tractogram& t, std::uint64_t i) {
  return {t.positions[3 * i], t.positions[3 * i + 1], t.positions[3 * i + 2]};
}

void expect_point_near(const vxl::Tractogram& t, std::uint64_t i, std::array<double, 3> want, double tol = 1e-4) {
  const auto p = point(t, i);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(p[k], want[k], tol) << "point " << i << " coordinate " << k;
}

void expect_same_points(const vxl::Tractogram& a, const vxl::Tractogram& b, double tol) {
  ASSERT_EQ(a.offsets, b.offsets);
  ASSERT_EQ(a.positions.size(), b.positions.size());
  double worst = 0;
  for (std::size_t i = 0; i < a.positions.size(); ++i)
    worst = std::max(worst, std::fabs(double(a.positions[i]) - b.positions[i]));
  EXPECT_LE(worst, tol);
}

TEST(ReadTrk, EveryFixtureHasTheDocumentedCounts) {
  VXL_REQUIRE_REAL_DATA();
  for (const auto& f : kTrkFixtures) {
    SCOPED_TRACE(f.file);
    const vxl::Tractogram t = vxl::read_trk(real(f.file));
    EXPECT_EQ(t.streamline_count(), f.streamlines);
    EXPECT_EQ(t.point_count(), f.points);
    EXPECT_EQ(t.offsets.front(), 0u);
    EXPECT_EQ(t.offsets.back(), t.point_count());
    EXPECT_EQ(t.source.format, "trk");
    EXPECT_EQ(t.source.dtype, "float32");
    EXPECT_EQ(t.source.path, real(f.file));
    EXPECT_EQ(t.source.xxh3_128.size(), 32u);
    for (float v : t.positions) ASSERT_TRUE(std::isfinite(v));
  }
}

TEST(ReadTrk, WarningsOnlyWhereTheHeaderIsIncomplete) {
  VXL_REQUIRE_REAL_DATA();
  for (const auto& f : kTrkFixtures) {
    SCOPED_TRACE(f.file);
    const vxl::Tractogram t = vxl::read_trk(real(f.file));
    const std::string name = f.file;
    if (name == "niivue__colby.trk") {
      EXPECT_TRUE(has_warning(t.source.warnings, "vox_to_ras is not recorded"));
      EXPECT_TRUE(has_warning(t.source.warnings, "voxel_order LPS disagrees"));
      EXPECT_EQ(t.source.warnings.size(), 2u);
      EXPECT_FALSE(t.source.vox_to_ras.has_value());
    } else if (name == "dipy__fbc34ca__tracks300.trk") {
      EXPECT_TRUE(has_warning(t.source.warnings, "version 1 header has no vox_to_ras"));
      EXPECT_TRUE(has_warning(t.source.warnings, "voxel_order is empty"));
      EXPECT_TRUE(has_warning(t.source.warnings, "voxel_size is not recorded"));
      EXPECT_EQ(t.source.warnings.size(), 3u);
      EXPECT_FALSE(t.source.vox_to_ras.has_value());
    } else if (name == "nibabel__standard.LPS.trk") {
      EXPECT_TRUE(has_warning(t.source.warnings, "voxel_order LPS disagrees with the orientation of vox_to_ras (RAS)"));
      EXPECT_EQ(t.source.warnings.size(), 1u);
    } else {
      EXPECT_TRUE(t.source.warnings.empty()) << t.source.warnings.front();
      EXPECT_TRUE(t.source.vox_to_ras.has_value());
    }
  }
}

// Reference values: nibabel 5.0.0 (Debian python3-nibabel), run in ../shared/data/real as
//   /usr/bin/python3 -W ignore -c "import nibabel as nib; s = nib.streamlines.load('FILE').streamlines;
//                                  print(s[0][:2].tolist(), s[-1][-1].tolist())"
// i.e. the first two points of the first streamline and the last point of the last one, in RAS mm.
struct Reference {
  const char* file;
  std::vector<std::array<double, 3>> first;  // the first points of streamline 0
  std::array<double, 3> last;
};

const Reference kReferences[] = {
    {"TractographyFormat__stroke.trk",
     {{63.7966423034668, -41.454803466796875, 2.3184967041015625},
      {60.35334014892578, -42.743751525878906, 1.0126876831054688}},
     {-64.24888610839844, -12.375511169433594, 1.8407669067382812}},
    {"niivue__stroke.trk.gz",
     {{63.7966423034668, -41.454803466796875, 2.3184967041015625},
      {60.35334014892578, -42.743751525878906, 1.0126876831054688}},
     {-64.24888610839844, -12.375511169433594, 1.8407669067382812}},
    {"nibabel__standard.LPS.trk", {{-0.5, -1.5, 1.0}, {0.0, 0.0, 2.0}}, {3.5, 13.5, 11.0}},
    {"niivue__colby.trk",
     {{191.5, -0.5, -0.5}, {191.5, -0.5, -0.46000000834465027}},
     {81.81547546386719, 83.7774887084961, 49.21125030517578}},
    // The first streamline of complex_big_endian.trk has a single point.
    {"nibabel__complex_big_endian.trk", {{0.0, 1.0, 2.0}}, {12.0, 13.0, 14.0}},
};

TEST(ReadTrk, MatchesNibabelReferencePoints) {
  VXL_REQUIRE_REAL_DATA();
  for (const auto& r : kReferences) {
    SCOPED_TRACE(r.file);
    const vxl::Tractogram t = vxl::read_trk(real(r.file));
    ASSERT_GT(t.streamline_count(), 0u);
    ASSERT_GE(t.offsets[1], r.first.size());
    for (std::size_t i = 0; i < r.first.size(); ++i) expect_point_near(t, i, r.first[i]);
    expect_point_near(t, t.point_count() - 1, r.last);
  }
}

TEST(ReadTrk, StrokeTrkAndGzipAgreeInRasMm) {
  VXL_REQUIRE_REAL_DATA();
  // Same streamlines stored under different headers (RAS + identity vs LAS + flipping vox_to_ras).
  const vxl::Tractogram a = vxl::read_trk(real("TractographyFormat__stroke.trk"));
  const vxl::Tractogram b = vxl::read_trk(real("niivue__stroke.trk.gz"));
  expect_same_points(a, b, 1e-4);
  EXPECT_EQ(a.source.header["voxel_order"], "RAS");
  EXPECT_EQ(b.source.header["voxel_order"], "LAS");
  EXPECT_EQ(b.source.header["compression"], "gzip");
  EXPECT_EQ(b.source.bytes, 2538041u);  // the compressed size on disk
  EXPECT_EQ(a.source.bytes, 2997668u);
  // The fixture's published first points: (63.797, -41.455, 2.318), (60.353, -42.744, 1.013).
  expect_point_near(b, 0, {63.797, -41.455, 2.318}, 1e-3);
}

TEST(ReadTrk, Tracks300VersionOneAndTwoHeadersAgree) {
  VXL_REQUIRE_REAL_DATA();
  // The v1 file has no geometry at all (voxel_size 0, no vox_to_ras): its points are world mm as
  // stored. The v2 re-save stores them + 0.5 with voxel_size 1 and identity vox_to_ras.
  const vxl::Tractogram v1 = vxl::read_trk(real("dipy__fbc34ca__tracks300.trk"));
  const vxl::Tractogram v2 = vxl::read_trk(real("dipy__tracks300.trk"));
  EXPECT_EQ(v1.source.header["version"], 1);
  EXPECT_EQ(v2.source.header["version"], 2);
  expect_same_points(v1, v2, 1e-4);
  // nibabel: s[0][0] of dipy__tracks300.trk
  expect_point_near(v1, 0, {92.29692840576172, 115.46074676513672, 66.92552185058594});
}

TEST(ReadTrk, BigEndianEqualsLittleEndian) {
  VXL_REQUIRE_REAL_DATA();
  const vxl::Tractogram le = vxl::read_trk(real("nibabel__complex.trk"));
  const vxl::Tractogram be = vxl::read_trk(real("nibabel__complex_big_endian.trk"));
  EXPECT_EQ(le.positions, be.positions);
  EXPECT_EQ(le.offsets, be.offsets);
  EXPECT_EQ(be.source.header["endianness"], "big");
  EXPECT_EQ(be.source.header["n_scalars"], 4);
  EXPECT_EQ(be.source.header["n_properties"], 5);
  EXPECT_EQ(le.source.header["scalar_names"], be.source.header["scalar_names"]);
}

TEST(ReadTrk, HeaderJsonHasTheDecodedFields) {
  VXL_REQUIRE_REAL_DATA();
  const vxl::Tractogram t = vxl::read_trk(real("niivue__colby.trk"));
  const auto& h = t.source.header;
  EXPECT_EQ(h["dim"], nlohmann::json({192, 192, 55}));
  EXPECT_EQ(h["voxel_size"], nlohmann::json({1.25, 1.25, 2.5}));
  EXPECT_EQ(h["voxel_order"], "LPS");
  EXPECT_EQ(h["n_scalars"], 3);
  EXPECT_EQ(h["scalar_names"].size(), 3u);
  EXPECT_EQ(h["n_count"], 2);
  EXPECT_EQ(h["version"], 2);
  EXPECT_TRUE(h.contains("vox_to_ras"));
  EXPECT_TRUE(h.contains("voxmm_to_rasmm"));
  EXPECT_NO_THROW((void)h.dump());

  const vxl::Tractogram s = vxl::read_trk(real("niivue__stroke.trk.gz"));
  ASSERT_TRUE(s.source.vox_to_ras.has_value());
  EXPECT_EQ((*s.source.vox_to_ras)[0], -1.0);
  EXPECT_EQ((*s.source.vox_to_ras)[3], 90.0);
  EXPECT_EQ((*s.source.vox_to_ras)[15], 1.0);
}

// ---- synthetic files ----

// A TRK header with the given fields, little- or big-endian.
struct TrkSpec {
  std::int32_t version = 2;
  std::array<std::int16_t, 3> dim = {10, 20, 30};
  std::array<float, 3> voxel_size = {2, 2, 2};
  std::array<float, 16> vox_to_ras = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  std::string voxel_order = "RAS";
  std::int16_t n_scalars = 0;
  std::int16_t n_properties = 0;
  std::int32_t n_count = 0;
  std::int32_t hdr_size = 1000;
  bool big_endian = false;
};

class TrkWriter {
 public:
  explicit TrkWriter(const TrkSpec& s) : big_(s.big_endian), bytes_(1000, 0) {
    std::memcpy(bytes_.data(), "TRACK", 5);
    for (int i = 0; i < 3; ++i) put16(6 + 2 * i, s.dim[i]);
    for (int i = 0; i < 3; ++i) putf(12 + 4 * i, s.voxel_size[i]);
    put16(36, s.n_scalars);
    put16(238, s.n_properties);
    for (int i = 0; i < 16; ++i) putf(440 + 4 * i, s.vox_to_ras[i]);
    std::memcpy(bytes_.data() + 948, s.voxel_order.data(), std::min<std::size_t>(4, s.voxel_order.size()));
    put32(988, s.n_count);
    put32(992, s.version);
    put32(996, s.hdr_size);
  }
  // Appends a record: int32 n then the given floats (points, scalars, properties as the caller lays them).
  TrkWriter& record(std::int32_t n, const std::vector<float>& floats) {
    std::size_t at = bytes_.size();
    bytes_.resize(at + 4 + 4 * floats.size());
    put32(at, n);
    for (std::size_t i = 0; i < floats.size(); ++i) putf(at + 4 + 4 * i, floats[i]);
    return *this;
  }
  std::vector<std::uint8_t>& bytes() { return bytes_; }
  std::string write(const vxl::test::ScratchDir& dir, const std::string& name) const {
    const std::string p = dir.file(name);
    std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(bytes_.data()), bytes_.size());
    return p;
  }

 private:
  void put32(std::size_t at, std::int32_t v) {
    std::uint32_t u = static_cast<std::uint32_t>(v);
    for (int i = 0; i < 4; ++i) bytes_[at + (big_ ? 3 - i : i)] = static_cast<std::uint8_t>(u >> (8 * i));
  }
  void put16(std::size_t at, std::int16_t v) {
    std::uint16_t u = static_cast<std::uint16_t>(v);
    for (int i = 0; i < 2; ++i) bytes_[at + (big_ ? 1 - i : i)] = static_cast<std::uint8_t>(u >> (8 * i));
  }
  void putf(std::size_t at, float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    put32(at, static_cast<std::int32_t>(u));
  }
  bool big_;
  std::vector<std::uint8_t> bytes_;
};

// Expects read_trk to throw an Input error whose message names the file (and the offset, if given).
void expect_input_error(const std::string& path, std::optional<std::uint64_t> offset, const std::string& part) {
  try {
    (void)vxl::read_trk(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const vxl::Error& e) {
    const std::string msg = e.what();
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << msg;
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(part), std::string::npos) << msg;
    if (offset) {
      EXPECT_EQ(e.offset(), offset) << msg;
      EXPECT_NE(msg.find("at byte " + std::to_string(*offset)), std::string::npos) << msg;
    }
  }
}

TEST(ReadTrkSynthetic, MapsVoxmmToRasAndReorientsLikeNibabel) {
  vxl::test::ScratchDir dir;
  TrkSpec s;  // voxel 2 mm, dims 10x20x30, identity vox_to_ras
  // (1,1,1) voxmm is the centre of voxel (0,0,0); (5,7,9) is voxel (2,3,4).
  const std::vector<float> pts = {1, 1, 1, 5, 7, 9};
  const auto ras = vxl::read_trk(TrkWriter(s).record(2, pts).write(dir, "ras.trk"));
  EXPECT_EQ(ras.positions, (std::vector<float>{0, 0, 0, 2, 3, 4}));
  EXPECT_TRUE(ras.source.warnings.empty());

  // voxel_order LPS under an RAS matrix: x and y mirror about the grid centre, i -> dim - 1 - i.
  s.voxel_order = "LPS";
  const auto lps = vxl::read_trk(TrkWriter(s).record(2, pts).write(dir, "lps.trk"));
  EXPECT_EQ(lps.positions, (std::vector<float>{9, 19, 0, 7, 16, 4}));
  EXPECT_TRUE(has_warning(lps.source.warnings, "disagrees"));

  // The same LPS order with a matching LPS matrix (plus a translation): no mirroring.
  s.vox_to_ras = {-1, 0, 0, 100, 0, -1, 0, 50, 0, 0, 1, -10, 0, 0, 0, 1};
  const auto lps2 = vxl::read_trk(TrkWriter(s).record(2, pts).write(dir, "lps2.trk"));
  EXPECT_EQ(lps2.positions, (std::vector<float>{100, 50, -10, 98, 47, -6}));
  EXPECT_TRUE(lps2.source.warnings.empty());

  // A permuted order (x and y swapped relative to the matrix): voxel axes are transposed.
  s.vox_to_ras = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  s.voxel_order = "ARS";
  const auto ars = vxl::read_trk(TrkWriter(s).record(2, pts).write(dir, "ars.trk"));
  EXPECT_EQ(ars.positions, (std::vector<float>{0, 0, 0, 3, 2, 4}));
}

TEST(ReadTrkSynthetic, SkipsScalarsAndProperties) {
  vxl::test::ScratchDir dir;
  TrkSpec s;
  s.voxel_size = {1, 1, 1};
  s.n_scalars = 2;
  s.n_properties = 1;
  TrkWriter w(s);
  w.record(2, {0.5f, 0.5f, 0.5f, 77, 78, 1.5f, 2.5f, 3.5f, 79, 80, /*property*/ 99});
  w.record(1, {4.5f, 5.5f, 6.5f, 81, 82, /*property*/ 98});
  const auto t = vxl::read_trk(w.write(dir, "scalars.trk"));
  EXPECT_EQ(t.offsets, (std::vector<std::uint64_t>{0, 2, 3}));
  EXPECT_EQ(t.positions, (std::vector<float>{0, 0, 0, 1, 2, 3, 4, 5, 6}));
}

TEST(ReadTrkSynthetic, BigEndianAndVersionOne) {
  vxl::test::ScratchDir dir;
  TrkSpec s;
  s.big_endian = true;
  s.voxel_order = "RAS";
  const auto be = vxl::read_trk(TrkWriter(s).record(1, {5, 7, 9}).write(dir, "be.trk"));
  EXPECT_EQ(be.positions, (std::vector<float>{2, 3, 4}));
  EXPECT_EQ(be.source.header["endianness"], "big");

  // Version 1: bytes 440..503 are not a matrix (garbage here); the identity is used, with a warning.
  s.big_endian = false;
  s.version = 1;
  s.vox_to_ras = {7, 7, 7, 7, 7, 7, 7, 7, 7, 7, 7, 7, 7, 7, 7, 7};
  const auto v1 = vxl::read_trk(TrkWriter(s).record(1, {5, 7, 9}).write(dir, "v1.trk"));
  EXPECT_EQ(v1.positions, (std::vector<float>{2, 3, 4}));
  EXPECT_FALSE(v1.source.vox_to_ras.has_value());
  EXPECT_TRUE(has_warning(v1.source.warnings, "version 1"));
}

TEST(ReadTrkSynthetic, StaleCountIsAWarningAndTheDataWins) {
  vxl::test::ScratchDir dir;
  TrkSpec s;
  s.n_count = 5;
  // (An empty record is malformed: HostileTrk.ZeroPointRecordIsMalformed.)
  const auto t = vxl::read_trk(TrkWriter(s).record(1, {1, 1, 1}).record(1, {2, 2, 2}).write(dir, "count.trk"));
  EXPECT_EQ(t.streamline_count(), 2u);
  EXPECT_TRUE(has_warning(t.source.warnings, "n_count is 5 but the file holds 2"));
  s.n_count = 2;
  const auto ok = vxl::read_trk(TrkWriter(s).record(1, {1, 1, 1}).record(1, {2, 2, 2}).write(dir, "count2.trk"));
  EXPECT_TRUE(ok.source.warnings.empty());
}

TEST(ReadTrkSynthetic, AllZeroVoxToRasMeansIdentity) {
  vxl::test::ScratchDir dir;
  TrkSpec s;
  s.vox_to_ras = {};
  const auto t = vxl::read_trk(TrkWriter(s).record(1, {5, 7, 9}).write(dir, "zero.trk"));
  EXPECT_EQ(t.positions, (std::vector<float>{2, 3, 4}));
  EXPECT_TRUE(has_warning(t.source.warnings, "not recorded"));
  EXPECT_FALSE(t.source.vox_to_ras.has_value());
}

TEST(ReadTrkBroken, TruncatedRecord) {
  vxl::test::ScratchDir dir;
  TrkWriter w{TrkSpec{}};
  w.record(2, {1, 1, 1, 2, 2, 2});
  w.record(5, {1, 1, 1, 2, 2, 2});  // claims 5 points, holds 2
  expect_input_error(w.write(dir, "trunc.trk"), 1000 + 4 + 24, "truncated streamline record #1");
}

TEST(ReadTrkBroken, TruncatedCount) {
  vxl::test::ScratchDir dir;
  TrkWriter w{TrkSpec{}};
  w.record(1, {1, 1, 1});
  w.bytes().push_back(0);
  w.bytes().push_back(0);
  expect_input_error(w.write(dir, "count.trk"), 1016, "4-byte point count");
}

TEST(ReadTrkBroken, NegativeAndHugePointCounts) {
  vxl::test::ScratchDir dir;
  expect_input_error(TrkWriter(TrkSpec{}).record(-3, {}).write(dir, "neg.trk"), 1000, "negative point count");
  expect_input_error(TrkWriter(TrkSpec{}).record(0x7FFFFFFF, {1, 2, 3}).write(dir, "huge.trk"), 1000,
                     "truncated streamline record #0");
}

TEST(ReadTrkBroken, BadHdrSize) {
  vxl::test::ScratchDir dir;
  TrkSpec s;
  s.hdr_size = 999;
  expect_input_error(TrkWriter(s).write(dir, "hdr.trk"), 996, "hdr_size");
}

TEST(ReadTrkBroken, ShortFileBadMagicBadOrder) {
  vxl::test::ScratchDir dir;
  TrkWriter w{TrkSpec{}};
  w.bytes().resize(500);
  expect_input_error(w.write(dir, "short.trk"), 500, "1000-byte TRK header");

  TrkWriter m{TrkSpec{}};
  m.bytes()[0] = 'X';
  expect_input_error(m.write(dir, "magic.trk"), 0, "TRACK");

  TrkSpec s;
  s.voxel_order = "LRS";
  expect_input_error(TrkWriter(s).write(dir, "order.trk"), 948, "voxel_order");

  TrkSpec z;
  z.vox_to_ras = {1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  // recorded but singular
  expect_input_error(TrkWriter(z).write(dir, "singular.trk"), 440, "singular");
}

TEST(ReadTrkBroken, UnsupportedVersionAndMissingFile) {
  vxl::test::ScratchDir dir;
  TrkSpec s;
  s.version = 7;
  const std::string p = TrkWriter(s).write(dir, "v7.trk");
  try {
    (void)vxl::read_trk(p);
    ADD_FAILURE() << "no error";
  } catch (const vxl::Error& e) {
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Unsupported);
    EXPECT_NE(std::string(e.what()).find(p), std::string::npos);
  }
  EXPECT_THROW((void)vxl::read_trk(dir.file("absent.trk")), vxl::Error);
}

TEST(ReadTrkBroken, TruncatedGzip) {
  VXL_REQUIRE_REAL_DATA();
  vxl::test::ScratchDir dir;
  std::vector<char> buf = vxl::test::slurp(real("niivue__stroke.trk.gz"));
  buf.resize(buf.size() / 2);
  const std::string p = dir.file("half.trk.gz");
  std::ofstream(p, std::ios::binary).write(buf.data(), static_cast<std::streamsize>(buf.size()));
  try {
    (void)vxl::read_trk(p);
    ADD_FAILURE() << "no error";
  } catch (const vxl::Error& e) {
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

}  // namespace
