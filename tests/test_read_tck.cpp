// TCK reader: real fixtures (the counts their upstream projects publish) and hand-made edge cases.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>

#include "converter/readers/mrtrix_header.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/read_tsf.h"
#include "converter/readers/tck_stream.h"
#include "format/base/error.h"
#include "tests/mrtrix_test_files.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::raw;
using test::real;
using test::ScratchDir;

// Writes a TCK with the given datatype from raw data bytes.
void write_tck(const std::string& path, const std::string& datatype, const std::string& data,
               const std::string& extra = "") {
  test::write_mrtrix_file(path, "mrtrix tracks", datatype, data, extra);
}

const float kNaN = NAN, kInf = INFINITY;

TEST(TckReader, RealFixtureCounts) {
  VXL_REQUIRE_REAL_DATA();
  struct Case {
    const char* name;
    std::uint64_t streamlines, points;
  } cases[] = {
      {"TractographyFormat__stroke.tck", 36763, 237468},
      {"TractographyFormat__example.tck", 305, 44249},
      {"niivue__tract.SLF1_R.tck", 13, 156},
      {"test_data__tracks.tck", 500, 3408},
      {"test_data__tckgen__tensor_det.tck", 257, 15355},
      {"test_data__tckresample__endpoints.tck", 500, 1000},
      {"test_data__SIFT_phantom__tracks.tck", 5000, 105802},
      {"mrtrix3__tmp.tck", 50000, 50000},
      {"nibabel__empty.tck", 0, 0},
      {"nibabel__simple.tck", 3, 8},
      {"nibabel__simple_big_endian.tck", 3, 8},
      {"nibabel__standard.tck", 120, 360},
      {"nibabel__matlab_nan.tck", 1, 108},
      {"nibabel__multiline_header_field.tck", 1, 253},
      {"scilpy__disco_centerlines_resampled.tck", 2000, 320358},
      {"trx-javascript__gs.tck", 13, 104},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Tractogram t = read_tck(real(c.name));
    EXPECT_EQ(t.streamline_count(), c.streamlines);
    EXPECT_EQ(t.point_count(), c.points);
    EXPECT_EQ(t.source.format, "tck");
    EXPECT_EQ(t.source.xxh3_128.size(), 32u);
  }
}

// Reference values from an independent reader, nibabel 5.x (Debian python3-nibabel), obtained with:
//   /usr/bin/python3 -c "import nibabel as nb; s=nb.streamlines.load('TractographyFormat__stroke.tck').streamlines;
//                        print([float(x) for x in s[0][0]], [float(x) for x in s[0][1]], [float(x) for x in
//                        s[-1][-1]])"
// TCK stores float32, so the comparison is exact.
TEST(TckReader, StrokeMatchesNibabel) {
  VXL_REQUIRE_REAL_DATA();
  Tractogram t = read_tck(real("TractographyFormat__stroke.tck"));
  ASSERT_GT(t.point_count(), 2u);
  const std::vector<float> first_two(t.positions.begin(), t.positions.begin() + 6);
  EXPECT_EQ(first_two, (std::vector<float>{63.7966423034668f, -41.454803466796875f, 2.3184967041015625f,
                                           60.35334014892578f, -42.743751525878906f, 1.0126876831054688f}));
  const std::vector<float> last(t.positions.end() - 3, t.positions.end());
  EXPECT_EQ(last, (std::vector<float>{-64.24888610839844f, -12.375511169433594f, 1.8407669067382812f}));
}

TEST(TckReader, StaleCountIsWarnedAndDataTrusted) {
  VXL_REQUIRE_REAL_DATA();
  Tractogram t = read_tck(real("nibabel__matlab_nan.tck"));
  EXPECT_EQ(t.streamline_count(), 1u);
  bool warned = false;
  for (const auto& w : t.source.warnings) warned |= w.find("615000") != std::string::npos;
  EXPECT_TRUE(warned);
}

TEST(TckReader, BigEndianEqualsLittleEndian) {
  VXL_REQUIRE_REAL_DATA();
  Tractogram le = read_tck(real("nibabel__simple.tck"));
  Tractogram be = read_tck(real("nibabel__simple_big_endian.tck"));
  EXPECT_EQ(le.positions, be.positions);
  EXPECT_EQ(le.offsets, be.offsets);
}

TEST(TckReader, MalformedFixturesAreRefusedWithTheFileName) {
  VXL_REQUIRE_REAL_DATA();
  for (const char* name :
       {"nibabel__no_header_end.tck", "nibabel__no_header_end_eof.tck", "nibabel__no_magic_number.tck"}) {
    SCOPED_TRACE(name);
    try {
      read_tck(real(name));
      ADD_FAILURE() << "accepted a malformed file";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

TEST(TckReader, AllFourDatatypes) {
  ScratchDir dir;
  for (bool big : {false, true}) {
    std::string f32 =
        raw<float>({1, 2, 3, 4, 5, 6, kNaN, kNaN, kNaN, 7, 8, 9, kNaN, kNaN, kNaN, kInf, kInf, kInf}, big);
    std::string f64 =
        raw<double>({1, 2, 3, 4, 5, 6, kNaN, kNaN, kNaN, 7, 8, 9, kNaN, kNaN, kNaN, kInf, kInf, kInf}, big);
    write_tck(dir.file("a.tck"), big ? "Float32BE" : "Float32LE", f32);
    write_tck(dir.file("b.tck"), big ? "Float64BE" : "Float64LE", f64);
    Tractogram a = read_tck(dir.file("a.tck"));
    Tractogram b = read_tck(dir.file("b.tck"));
    std::vector<float> expected = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    EXPECT_EQ(a.positions, expected);
    EXPECT_EQ(b.positions, expected);
    EXPECT_EQ(a.offsets, (std::vector<std::uint64_t>{0, 2, 3}));
    EXPECT_EQ(b.offsets, a.offsets);
  }
}

TEST(TckReader, MissingInfTerminatorIsTolerated) {
  ScratchDir dir;
  write_tck(dir.file("a.tck"), "Float32LE", raw<float>({1, 2, 3, 4, 5, 6, kNaN, kNaN, kNaN}));
  Tractogram t = read_tck(dir.file("a.tck"));
  EXPECT_EQ(t.streamline_count(), 1u);
  EXPECT_FALSE(t.source.warnings.empty());
}

TEST(TckReader, UnknownDatatypeIsUnsupported) {
  ScratchDir dir;
  write_tck(dir.file("a.tck"), "Int16LE", raw<float>({kInf, kInf, kInf}));
  try {
    read_tck(dir.file("a.tck"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
  }
}

// The datatypes and the refusal of others are one helper (mrtrix_header.h) for the TCK reader, its
// streamed form and the TSF reader: each type reaches the decoder as its own Real and byte order, and every
// reader refuses the same way, naming its format.
TEST(TckReader, DatatypesAreOneListForTckTsfAndTheStream) {
  struct Decoded {
    std::size_t bytes;
    bool big;
    bool operator==(const Decoded&) const = default;
  };
  auto decoded = [](const char* datatype) {
    return visit_mrtrix_datatype(mrtrix_datatype("x", datatype, kTckFile), []<typename Real, bool kBigEndian>() {
      return Decoded{sizeof(Real), kBigEndian};
    });
  };
  EXPECT_EQ(decoded("Float32LE"), (Decoded{4, false}));
  EXPECT_EQ(decoded("Float32BE"), (Decoded{4, true}));
  EXPECT_EQ(decoded("Float64LE"), (Decoded{8, false}));
  EXPECT_EQ(decoded("Float64BE"), (Decoded{8, true}));

  ScratchDir dir;
  write_tck(dir.file("a.tck"), "Float32", raw<float>({kInf, kInf, kInf}));
  test::write_mrtrix_file(dir.file("a.tsf"), "mrtrix track scalars", "Float32", raw<float>({kInf}));
  auto error_of = [](auto read) -> std::string {
    try {
      read();
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
      return e.what();
    }
    return "no error";
  };
  const std::string expected = " datatype 'Float32' (expected Float32LE, Float32BE, Float64LE or Float64BE)";
  EXPECT_EQ(error_of([&] { (void)read_tck(dir.file("a.tck")); }), dir.file("a.tck") + ": TCK" + expected);
  EXPECT_EQ(error_of([&] { TckStream s(dir.file("a.tck"), 1 << 20); }), dir.file("a.tck") + ": TCK" + expected);
  EXPECT_EQ(error_of([&] { (void)read_tsf(dir.file("a.tsf")); }), dir.file("a.tsf") + ": TSF" + expected);
}

TEST(TckReader, NonFiniteCoordinateInsideAStreamlineIsRefusedWithItsOffset) {
  ScratchDir dir;
  write_tck(dir.file("a.tck"), "Float32LE", raw<float>({1, 2, 3, 4, kNaN, 6, kNaN, kNaN, kNaN, kInf, kInf, kInf}));
  try {
    read_tck(dir.file("a.tck"));
    FAIL();
  } catch (const Error& e) {
    ASSERT_TRUE(e.offset().has_value());
    EXPECT_NE(std::string(e.what()).find("non-finite"), std::string::npos);
  }
}

TEST(TckReader, DataOffsetPastEndIsRefused) {
  ScratchDir dir;
  std::ofstream(dir.file("a.tck")) << "mrtrix tracks\ndatatype: Float32LE\nfile: . 5000\nEND\n";
  EXPECT_THROW(read_tck(dir.file("a.tck")), Error);
}

}  // namespace
}  // namespace vxl
