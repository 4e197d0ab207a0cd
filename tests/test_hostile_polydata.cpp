// Hostile legacy VTK and XML VTP files (tests/hostile_inputs.h writes them): counts that wrap, cells
// numbered against VTK's rules, arrays that say more or less than they hold. Each must be refused with the
// documented kind of error, naming the file, and the command line must write nothing.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "converter/readers/read_tractogram.h"
#include "format/checked_count.h"
#include "format/error.h"
#include "format/vxl_file.h"
#include "tests/hostile_inputs.h"
#include "tests/test_support.h"

namespace {

namespace hostile = vxl::test::hostile;
using vxl::test::ScratchDir;

// The error `read` throws, or a failure when it throws none.
template <typename Read>
vxl::Error error_of(Read read) {
  try {
    read();
  } catch (const vxl::Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error";
  return vxl::Error(vxl::ErrorKind::Usage, "", std::nullopt, "no error");
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

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

// Counts far beyond what an array holds were refused as "a likely decompression bomb" (exit 4) before
// the array's own headers were read, also where nothing is compressed; a count its bytes, text or block
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

// A VTK array named %00 became a value set named "" (the empty-name rule came before the NUL), a%00b was
// cut to a; `verify` passed the file and `export .trx` refused it (exit 4). Names are mapped at conversion
// to ones every command accepts, each change warned about.
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

}  // namespace
