// Hostile legacy VTK and XML VTP files (tests/hostile_inputs.h writes them): counts that wrap, cells
// numbered against VTK's rules, arrays that say more or less than they hold. Each must be refused with the
// documented kind of error, naming the file, and the command line must write nothing.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "converter/readers/read_tractogram.h"
#include "format/base/checked_count.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "tests/hostile_inputs.h"
#include "tests/test_support.h"

namespace {

namespace hostile = vxl::test::hostile;
using hostile::error_of;
using vxl::test::ScratchDir;

using vxl::test::contains;

// `convert IN OUT.vxl` exits with `code`, names IN and leaves nothing at OUT.
void expect_convert_refused(const ScratchDir& dir, const std::string& in, int code) {
  const std::string out = dir.file("out.vxl");
  const auto r = vxl::test::run_cli("convert " + vxl::test::q(in) + " " + vxl::test::q(out));
  EXPECT_EQ(r.exit_code, code) << r.output;
  EXPECT_TRUE(contains(r.output, std::filesystem::path(in).filename().string())) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(CheckedCount, ProductsAndSumsBeyond64BitsAreRefused) {
  constexpr std::uint64_t max = ~std::uint64_t(0);
  EXPECT_EQ(vxl::count_product(3, 6148914691236517205u), std::optional<std::uint64_t>(max));
  EXPECT_FALSE(vxl::count_product(3, 6148914691236517206u));
  EXPECT_FALSE(vxl::count_product(std::uint64_t(1) << 32, std::uint64_t(1) << 32));
  EXPECT_EQ(vxl::count_product(0, max), std::optional<std::uint64_t>(0));
  EXPECT_EQ(vxl::count_sum(max - 1, 1), std::optional<std::uint64_t>(max));
  EXPECT_FALSE(vxl::count_sum(max, 1));
  const vxl::Error e = error_of([] { (void)vxl::checked_product(3, max, "f.vtk", 12, "POINTS count"); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input);
  EXPECT_EQ(std::string(e.what()), "f.vtk: at byte 12: POINTS count: 3 x 18446744073709551615 does not fit in 64 bits");
}

// 3 x N wraps to 2, 8 and 1 values: the file holds exactly that many, so only the product's overflow
// tells the count is a lie.
TEST(HostileVtk, PointsCountWhoseTripleWrapsIsMalformed) {
  ScratchDir dir;
  for (const std::uint64_t n : {6148914691236517206u, 6148914691236517208u, 12297829382473034411u})
    for (const bool binary : {false, true}) {
      SCOPED_TRACE(std::to_string(n) + (binary ? " BINARY" : " ASCII"));
      const std::string p = dir.file("points.vtk");
      hostile::vtk_points_count_wraps(p, n, binary);
      const vxl::Error e = error_of([&] { (void)vxl::read_tractogram(p); });
      EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
      EXPECT_TRUE(contains(e.what(), "POINTS count: 3 x " + std::to_string(n) + " does not fit in 64 bits"))
          << e.what();
      EXPECT_TRUE(e.offset().has_value()) << e.what();
      expect_convert_refused(dir, p, 3);
    }
}

// NumberOfVerts (or Polys, Strips) near 2^64 makes the sum of the cells wrap back to the 3 tuples the cell
// data holds; the lines' cell values would then be read far before the array.
TEST(HostileVtp, CellCountsThatWrapAreMalformed) {
  ScratchDir dir;
  constexpr std::uint64_t max = ~std::uint64_t(0);
  struct Counts {
    std::uint64_t verts, polys, strips;
  };
  for (const Counts c : {Counts{max, 1, 0}, Counts{max - 2, 3, 0}, Counts{1, max, 0}, Counts{0, 2, max - 1}}) {
    SCOPED_TRACE(std::to_string(c.verts) + " " + std::to_string(c.polys) + " " + std::to_string(c.strips));
    const std::string p = dir.file("cells.vtp");
    hostile::vtp_cell_count_wraps(p, c.verts, c.polys, c.strips);
    const vxl::Error e = error_of([&] { (void)vxl::read_tractogram(p); });
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
    EXPECT_TRUE(contains(e.what(), "does not fit in 64 bits")) << e.what();
    expect_convert_refused(dir, p, 3);
  }
}

// Counts far beyond what an array holds are not refused as "a likely decompression bomb" (exit 4) before
// the array's own headers are read, also where nothing is compressed: a count its bytes, text or block
// headers contradict is malformed (exit 3). Only data that agrees with its count is held to the budget.
TEST(HostileVtp, CountsBeyondWhatTheArraysHoldAreMalformed) {
  ScratchDir dir;
  std::vector<vxl::test::VtpStyle> styles(6);
  styles[1].format = "ascii";
  styles[2].format = styles[3].format = styles[5].format = "appended";
  styles[3].appended_base64 = true;
  styles[4].zlib = styles[5].zlib = true;
  for (const vxl::test::VtpStyle& style : styles)
    for (const std::uint64_t points : {std::uint64_t{6}, std::uint64_t{100000000}, std::uint64_t{1} << 40}) {
      SCOPED_TRACE(style.format + (style.appended_base64 ? " base64" : "") + (style.zlib ? " zlib " : " ") +
                   std::to_string(points));
      const std::string p = dir.file("counts.vtp");
      hostile::vtp_points_beyond_arrays(p, style, points);
      const vxl::Error e = error_of([&] { (void)vxl::read_tractogram(p); });
      EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
      EXPECT_TRUE(contains(e.what(), "Points")) << e.what();
      expect_convert_refused(dir, p, 3);
    }
}

// VTK array names that decode to a NUL (%00, a%00b), a path separator, ".." or a backslash neither become
// an empty name nor are cut at the NUL: names are mapped at conversion to ones every command accepts
// (`verify` and `export .trx` both take the file), each change warned about.
TEST(HostileVtk, ArrayNamesAreMappedToNamesEveryCommandAccepts) {
  ScratchDir dir;
  const std::string in = dir.file("names.vtk"), vxl = dir.file("names.vxl");
  // Decoded: "\0", "a\0b", "a", "x/y", "x%2Fy", "..", "back\\slash".
  hostile::vtk_point_arrays_named(in, {"%00", "a%00b", "a", "x%2Fy", "x%252Fy", "..", "back\\slash"});
  const auto c = vxl::test::run_cli("convert " + vxl::test::q(in) + " " + vxl::test::q(vxl));
  ASSERT_EQ(c.exit_code, 0) << c.output;
  EXPECT_TRUE(contains(c.output, "value set '\\0' written as '%00'")) << c.output;
  EXPECT_TRUE(contains(c.output, "value set 'x%2Fy' written as 'x%2Fy (2)'")) << c.output;
  const vxl::VxlFile f = vxl::VxlFile::open(vxl);
  std::vector<std::string> names;
  for (std::uint32_t k = 0; k < f.vertex_values().size(); ++k) names.push_back(f.vertex_values().name(k));
  EXPECT_EQ(names, (std::vector<std::string>{"%00", "a%00b", "a", "x%2Fy", "x%2Fy (2)", "%2E%2E", "back%5Cslash"}));
  for (const std::string& args :
       {"verify " + vxl::test::q(vxl), "export " + vxl::test::q(vxl) + " " + vxl::test::q(dir.file("names.trx"))}) {
    const auto r = vxl::test::run_cli(args);
    EXPECT_EQ(r.exit_code, 0) << args << ": " << r.output;
  }
}

// Malformed files that must not be read as something else: fractional offsets (1.5 is not read as 1),
// integer arrays with fractions, an ASCII array longer than declared. Each is malformed.
TEST(HostileVtk, FractionsAndSurplusValuesAreMalformed) {
  ScratchDir dir;
  const std::string head =
      "# vtk DataFile Version 5.1\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 1 1 2 2 2\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {head + "LINES 3 3\nOFFSETS vtktypeint64\n0 1.5 3\nCONNECTIVITY vtktypeint64\n0 1 2\n",
       "LINES OFFSETS: expected an integer, found '1.5'"},
      {head + "LINES 2 3\nOFFSETS vtktypeint64\n0 3\nCONNECTIVITY vtktypeint64\n0 1 2.5\n",
       "LINES CONNECTIVITY: expected an integer, found '2.5'"},
      {head + "LINES 1 4\n3 0 1 2 7\n", ""},
      {"# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n0 0 0 1 1 1 7\nLINES 1 3\n2 0 1\n",
       ""}};
  for (const auto& [text, message] : cases) {
    SCOPED_TRACE(text);
    const std::string p = dir.file("f.vtk");
    hostile::write_file(p, text);
    const vxl::Error e = error_of([&] { (void)vxl::read_tractogram(p); });
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
    EXPECT_TRUE(contains(e.what(), message)) << e.what();
  }
}

TEST(HostileVtp, FractionalOffsetsAndSurplusAsciiValuesAreMalformed) {
  ScratchDir dir;
  vxl::test::VtpStyle ascii;
  ascii.format = "ascii";
  const std::string valid = vxl::test::small_vtp(ascii);
  const std::string offsets = ">3 4 6 <", points = ">0.5 1.25 -2 ";
  ASSERT_TRUE(contains(valid, offsets));
  ASSERT_TRUE(contains(valid, points));
  const std::vector<std::pair<std::string, std::string>> cases = {
      {std::string(valid).replace(valid.find(offsets), offsets.size(), ">2.5 4 6 <"), "expected an integer"},
      {std::string(valid).replace(valid.find(offsets), offsets.size(), ">3 4 6 7 <"),
       "more values than the 3 declared"},
      {std::string(valid).replace(valid.find(points), points.size(), ">0.5 1.25 -2 9 "), "more values than the 15"}};
  for (const auto& [text, message] : cases) {
    const std::string p = dir.file("f.vtp");
    hostile::write_file(p, text);
    const vxl::Error e = error_of([&] { (void)vxl::read_tractogram(p); });
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
    EXPECT_TRUE(contains(e.what(), message)) << e.what();
  }
  // Float offsets that are whole numbers stay valid.
  vxl::test::VtpBuilder b({});
  const vxl::test::SmallPolyData d;
  const std::string body = "<Points>\n" + b.data_array("Float32", "Points", 3, d.points) + "</Points>\n<Lines>\n" +
                           b.data_array("Int32", "connectivity", 1, d.connectivity) +
                           b.data_array("Float32", "offsets", 1, std::vector<float>{3, 4, 6}) + "</Lines>\n";
  hostile::write_file(dir.file("float.vtp"), b.file("NumberOfPoints=\"5\" NumberOfLines=\"3\"", body));
  EXPECT_EQ(vxl::read_tractogram(dir.file("float.vtp")).streamline_count(), 3u);
  vxl::test::VtpBuilder c({});
  const std::string fractional = "<Points>\n" + c.data_array("Float32", "Points", 3, d.points) +
                                 "</Points>\n<Lines>\n" + c.data_array("Int32", "connectivity", 1, d.connectivity) +
                                 c.data_array("Float32", "offsets", 1, std::vector<float>{1.5f, 4, 6}) + "</Lines>\n";
  hostile::write_file(dir.file("fraction.vtp"), c.file("NumberOfPoints=\"5\" NumberOfLines=\"3\"", fractional));
  EXPECT_TRUE(contains(error_of([&] { (void)vxl::read_tractogram(dir.file("fraction.vtp")); }).what(),
                       "offsets must be non-decreasing integers; offset 0 is 1.5"));
}

// Bytes after a block's zlib stream, inside its declared compressed size, are not ignored: malformed.
TEST(HostileVtp, JunkAfterAZlibStreamIsMalformed) {
  ScratchDir dir;
  const std::string p = dir.file("z.vtp");
  hostile::vtp_zlib_block_with_junk(p, "");
  EXPECT_EQ(vxl::read_tractogram(p).point_count(), 2u);
  hostile::vtp_zlib_block_with_junk(p, "JUNK");
  const vxl::Error e = error_of([&] { (void)vxl::read_tractogram(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
  EXPECT_TRUE(contains(e.what(), "junk after the zlib stream")) << e.what();
}

// VTK numbers cells vertices first, then lines, whatever order the file lists them in: with VERTICES after
// LINES the line keeps its own cell value (42), not the vertex's (10).
TEST(HostileVtk, VerticesAfterLinesStillComeFirstInCellData) {
  ScratchDir dir;
  const std::string p = dir.file("v.vtk");
  hostile::write_file(
      p,
      "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 1 1 2 2 2\n"
      "LINES 1 3\n2 0 1\nVERTICES 1 2\n1 2\nCELL_DATA 2\nSCALARS c float 1\nLOOKUP_TABLE default\n10 42\n");
  const vxl::Tractogram t = vxl::read_tractogram(p);
  ASSERT_EQ(t.streamline_values.size(), 1u);
  EXPECT_EQ(t.streamline_values[0].values, std::vector<float>{42});
}

// A valid VTP is read when a comment before the data names <AppendedData>: the block is found as an
// element, not by a text search, and a '>' inside a quoted attribute of the real tag does not cut it short.
TEST(HostileVtp, AppendedDataIsFoundAsAnElementNotAsText) {
  ScratchDir dir;
  for (const bool base64 : {false, true}) {
    vxl::test::VtpStyle style;
    style.format = "appended";
    style.appended_base64 = base64;
    style.zlib = true;
    std::string s = vxl::test::small_vtp(style);
    const std::size_t root = s.find("<PolyData>");
    ASSERT_NE(root, std::string::npos);
    s.insert(root, "<!-- the arrays are in <AppendedData encoding=\"raw\"> _ below -->\n");
    const std::string tag = "<AppendedData encoding=";
    s.insert(s.find(tag) + std::string("<AppendedData").size(), " note=\"a > b\"");
    const std::string p = dir.file("comment.vtp");
    hostile::write_file(p, s);
    const vxl::Tractogram t = vxl::read_tractogram(p);
    EXPECT_EQ(t.streamline_count(), 3u);
    EXPECT_EQ(t.point_count(), 6u);
  }
}

}  // namespace
