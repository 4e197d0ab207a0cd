// TRX dpg (a row of values per group) through the whole pipeline: read from a TRX zip or directory in
// its dtype, stored as the .vxl's GDAT (spec §5.13), packed and unpacked (.vxlz §4.8), exported back to
// TRX byte for byte, listed by `info`, warned about by the exports that have no place for them; and TRX
// groups that list an index twice (a set, with a warning giving the count).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "converter/export/export_groups.h"
#include "converter/export/export_tck.h"
#include "converter/export/export_trk.h"
#include "converter/export/export_trx.h"
#include "converter/package/pack.h"
#include "converter/package/unpack.h"
#include "converter/readers/read_tractogram.h"
#include "converter/selection/selection_output.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_group_values.h"
#include "format/vxl_verify.h"
#include "tests/export_test_support.h"
#include "tests/test_support.h"
#include "tests/zip_writer.h"

namespace vxl {
namespace {

using test::Bytes;
using test::has_warning;
using test::q;
using test::ScratchDir;

template <typename T>
Bytes le_bytes(const std::vector<T>& values) {
  Bytes out(values.size() * sizeof(T));
  std::memcpy(out.data(), values.data(), out.size());  // the test machines are little-endian, as TRX
  return out;
}

Bytes text(const std::string& s) { return Bytes(s.begin(), s.end()); }

// A NaN with a payload and a negative zero: bit patterns no float conversion would keep.
const std::uint64_t kNanBits = 0x7FF800000000BEEFull;
const std::uint64_t kMinusZeroBits = 0x8000000000000000ull;

// 3 streamlines; group "bundle A" lists streamline 2 twice (a member may list at most NB_STREAMLINES
// entries), group "B" holds streamline 1; four rows of values per group in four dtypes.
std::vector<std::pair<std::string, Bytes>> trx_members() {
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 5, 0, 1, 5, 0, 2, 5, 0, 0, 9, 9};
  return {
      {"header.json", text("{\"DIMENSIONS\": [10, 10, 10], \"VOXEL_TO_RASMM\": "
                           "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \"NB_STREAMLINES\": 3, \"NB_VERTICES\": 6}")},
      {"positions.3.float32", le_bytes(positions)},
      {"offsets.uint64", le_bytes(std::vector<std::uint64_t>{0, 2, 5, 6})},
      {"groups/bundle A.uint16", le_bytes(std::vector<std::uint16_t>{2, 0, 2})},
      {"groups/B.int32", le_bytes(std::vector<std::int32_t>{1})},
      {"dpg/bundle A/color.3.uint8", Bytes{255, 128, 0}},
      {"dpg/bundle A/mean_fa.float16", le_bytes(std::vector<std::uint16_t>{0x3800})},  // 0.5
      {"dpg/B/volume.uint32", le_bytes(std::vector<std::uint32_t>{123456})},
      {"dpg/B/odd.2.float64", le_bytes(std::vector<std::uint64_t>{kNanBits, kMinusZeroBits})}};
}

using test::write_dir;

// The rows as "group/name.n.dtype" -> bytes, independent of order and of group indices.
std::map<std::string, Bytes> rows_by_member(const std::vector<StreamlineGroup>& groups,
                                            const std::vector<GroupValues>& rows) {
  std::map<std::string, Bytes> out;
  for (const GroupValues& v : rows) {
    EXPECT_LT(v.group, groups.size());
    if (v.group >= groups.size()) continue;
    out[groups[v.group].name + "/" + v.name + "." + std::to_string(v.components) + "." +
        group_value_type_name(v.type)] = v.bytes;
  }
  return out;
}

const std::map<std::string, Bytes>& expected_rows() {
  static const std::map<std::string, Bytes> rows = {
      {"bundle A/color.3.uint8", Bytes{255, 128, 0}},
      {"bundle A/mean_fa.1.float16", le_bytes(std::vector<std::uint16_t>{0x3800})},
      {"B/volume.1.uint32", le_bytes(std::vector<std::uint32_t>{123456})},
      {"B/odd.2.float64", le_bytes(std::vector<std::uint64_t>{kNanBits, kMinusZeroBits})}};
  return rows;
}

std::vector<std::uint64_t> members_of(const std::vector<StreamlineGroup>& groups, const std::string& name) {
  for (const StreamlineGroup& g : groups)
    if (g.name == name) return g.members;
  ADD_FAILURE() << "no group " << name;
  return {};
}

TEST(TrxGroupValues, ReadFromZipAndDirectoryInTheirDtype) {
  ScratchDir dir;
  test::write_zip(dir.file("a.trx"), trx_members());
  write_dir(dir.file("a_dir.trx"), trx_members());
  for (const char* name : {"a.trx", "a_dir.trx"}) {
    SCOPED_TRACE(name);
    const Tractogram t = read_trx(dir.file(name));
    EXPECT_EQ(rows_by_member(t.groups, t.group_values), expected_rows());
    EXPECT_EQ(members_of(t.groups, "bundle A"), (std::vector<std::uint64_t>{0, 2}));
    EXPECT_EQ(members_of(t.groups, "B"), (std::vector<std::uint64_t>{1}));
    // The one warning: the repeats of "bundle A", with their count.
    EXPECT_EQ(t.source.warnings, (std::vector<std::string>{"group bundle A: 1 duplicate indices collapsed (3 listed "
                                                           "in groups/bundle A.uint16, 2 streamlines)"}));
  }
}

TEST(TrxGroupValues, MalformedRowsAreSkippedWithAWarning) {
  ScratchDir dir;
  auto members = trx_members();
  members.push_back({"dpg/nobody/x.float32", le_bytes(std::vector<float>{1})});  // no such group
  members.push_back({"dpg/B/short.3.uint8", Bytes{1, 2}});                       // 2 bytes for 3
  members.push_back({"dpg/B/words.text", text("hello")});                        // no dtype
  members.push_back({"dpg/loose.float32", le_bytes(std::vector<float>{1})});     // no group folder
  members.push_back({"dpg/B/volume.uint64", Bytes(8, 1)});                       // B/volume again
  members.push_back({"dpg/B/huge.99999999999999999999.uint8", Bytes{1}});        // count out of range
  test::write_zip(dir.file("m.trx"), members);
  const Tractogram t = read_trx(dir.file("m.trx"));
  EXPECT_EQ(t.streamline_count(), 3u);
  EXPECT_EQ(rows_by_member(t.groups, t.group_values), expected_rows());
  EXPECT_TRUE(has_warning(t.source.warnings, "dpg/nobody/x.float32: no groups/nobody.<dtype> member; ignored"));
  EXPECT_TRUE(has_warning(t.source.warnings, "dpg/B/short.3.uint8: holds 2 bytes, expected one row of 3 x 1"));
  EXPECT_TRUE(has_warning(t.source.warnings, "dpg/B/words.text: not dpg/<group>/<name>"));
  EXPECT_TRUE(has_warning(t.source.warnings, "dpg/loose.float32: not dpg/<group>/<name>"));
  EXPECT_TRUE(has_warning(t.source.warnings, "dpg/B/volume.uint64: a second dpg/B/volume"));
  EXPECT_TRUE(has_warning(t.source.warnings, "dpg/B/huge.99999999999999999999.uint8: holds 1 bytes"));
}

TEST(TrxGroupValues, SurviveConvertPackUnpackAndExportByteForByte) {
  ScratchDir dir;
  test::write_zip(dir.file("a.trx"), trx_members());
  const Tractogram source = read_trx(dir.file("a.trx"));
  ConvertSettings settings;  // packed positions, the default
  convert_tractogram(read_trx(dir.file("a.trx")), dir.file("a.vxl"), settings);
  {
    const VxlFile a = VxlFile::open(dir.file("a.vxl"));
    ASSERT_NE(a.find_section(section_id("GDAT")), nullptr);
    EXPECT_EQ(rows_by_member(a.groups(), a.group_values()), expected_rows());
    EXPECT_TRUE(verify_vxl(dir.file("a.vxl")).valid);
    pack_vxl(a, dir.file("a.vxlz"), PackSettings{});
  }
  unpack_vxlz(dir.file("a.vxlz"), dir.file("b.vxl"), UnpackSettings{});
  EXPECT_EQ(unpacked_vxl_bytes(VxlzFile::open(dir.file("a.vxlz")), UnpackSettings{}),
            std::filesystem::file_size(dir.file("b.vxl")))
      << "the groups' and their values' sizes, known from the package's tables";
  const VxlFile b = VxlFile::open(dir.file("b.vxl"));
  EXPECT_TRUE(verify_vxl(dir.file("b.vxl")).valid);
  EXPECT_EQ(rows_by_member(b.groups(), b.group_values()), expected_rows());
  // The unpacked GDAT is the converted one, byte for byte.
  const VxlFile a = VxlFile::open(dir.file("a.vxl"));
  EXPECT_EQ(encode_group_values(b.group_values()), encode_group_values(a.group_values()));

  export_trx(b, dir.file("b.trx"));
  const Tractogram back = read_trx(dir.file("b.trx"));
  EXPECT_EQ(rows_by_member(back.groups, back.group_values), expected_rows());
  EXPECT_EQ(members_of(back.groups, "bundle A"), (std::vector<std::uint64_t>{0, 2}));
  EXPECT_TRUE(back.source.warnings.empty()) << back.source.warnings.front();  // each member once now
  // The member names TRX tools look for: the component count only when above 1.
  const auto& names = back.source.header["_members"];
  for (const char* m :
       {"dpg/bundle A/color.3.uint8", "dpg/bundle A/mean_fa.float16", "dpg/B/volume.uint32", "dpg/B/odd.2.float64"})
    EXPECT_NE(std::find(names.begin(), names.end(), m), names.end()) << m;

  // A subset keeps every group, and so every row.
  const StreamlineSubset only_b = group_subset(b, "B");
  export_trx(b, dir.file("only_b.trx"), &only_b);
  const Tractogram subset = read_trx(dir.file("only_b.trx"));
  EXPECT_EQ(subset.streamline_count(), 1u);
  EXPECT_EQ(rows_by_member(subset.groups, subset.group_values), expected_rows());
  // So does a selection written as a .vxl (`select … OUT.vxl`), and one written as a .vtk says what it drops.
  EXPECT_TRUE(write_selection(b, only_b, dir.file("only_b.vxl"), {}, {}).empty());
  const VxlFile selected = VxlFile::open(dir.file("only_b.vxl"));
  EXPECT_EQ(rows_by_member(selected.groups(), selected.group_values()), expected_rows());
  EXPECT_TRUE(has_warning(write_selection(b, only_b, dir.file("only_b.vtk"), {}, {}),
                          "4 row(s) of values per group (TRX dpg) not written: a VTK"));
}

TEST(TrxGroupValues, ExportsWithoutAPlaceForThemWarn) {
  ScratchDir dir;
  test::write_zip(dir.file("a.trx"), trx_members());
  const VxlFile f = VxlFile::open(test::convert_float32(read_trx(dir.file("a.trx")), dir.file("a.vxl")));
  const ExportSummary tck = export_tck(f, dir.file("a.tck"));
  EXPECT_TRUE(has_warning(tck.warnings, "4 row(s) of values per group (TRX dpg) not written: a TCK has no place"));
  EXPECT_TRUE(has_warning(tck.warnings, "'bundle A/color'"));
  TckExportSettings one_group;
  one_group.group = "B";
  const ExportSummary b = export_tck(f, dir.file("b.tck"), one_group);
  EXPECT_TRUE(has_warning(b.warnings, "2 row(s) of values per group (TRX dpg) not written: a TCK"));
  EXPECT_TRUE(has_warning(export_trk(f, dir.file("a.trk")).warnings,
                          "4 row(s) of values per group (TRX dpg) not "
                          "written: a TRK"));
  const test::CommandResult vtk = test::run_cli("export " + q(dir.file("a.vxl")) + " " + q(dir.file("a.vtk")));
  EXPECT_EQ(vtk.exit_code, 0) << vtk.output;
  EXPECT_NE(vtk.output.find("4 row(s) of values per group (TRX dpg) not written: a VTK"), std::string::npos)
      << vtk.output;
  // A .trx has the place: no such warning.
  const test::CommandResult trx = test::run_cli("export " + q(dir.file("a.vxl")) + " " + q(dir.file("a2.trx")));
  EXPECT_EQ(trx.exit_code, 0) << trx.output;
  EXPECT_EQ(trx.output.find("not written"), std::string::npos) << trx.output;
}

TEST(TrxGroupValues, InfoListsTheRows) {
  ScratchDir dir;
  test::write_zip(dir.file("a.trx"), trx_members());
  const test::CommandResult convert = test::run_cli("convert " + q(dir.file("a.trx")) + " " + q(dir.file("a.vxl")));
  ASSERT_EQ(convert.exit_code, 0) << convert.output;
  EXPECT_NE(convert.output.find("group bundle A: 1 duplicate indices collapsed"), std::string::npos) << convert.output;
  const test::CommandResult json = test::run_cli("info --json " + q(dir.file("a.vxl")));
  ASSERT_EQ(json.exit_code, 0) << json.output;
  const nlohmann::json j = nlohmann::json::parse(json.output);
  bool found = false;
  for (const auto& g : j["groups"])
    if (g["name"] == "bundle A")
      for (const auto& v : g["values"])
        if (v["name"] == "color") {
          found = true;
          EXPECT_EQ(v["dtype"], "uint8");
          EXPECT_EQ(v["components"], 3);
          EXPECT_EQ(v["values"], nlohmann::json::array({255, 128, 0}));
        }
  EXPECT_TRUE(found) << json.output;
  const test::CommandResult info = test::run_cli("info " + q(dir.file("a.vxl")));
  EXPECT_NE(info.output.find("values      color (uint8 x 3): 255 128 0"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("values      mean_fa (float16 x 1): 0.5"), std::string::npos) << info.output;
}

// ---- the GDAT section itself ----

[[noreturn]] void throw_at(std::uint64_t position, const std::string& what) {
  throw std::runtime_error(std::to_string(position) + ": " + what);
}

std::string decode_error(const Bytes& payload, std::uint64_t group_count) {
  try {
    (void)decode_group_values(payload, group_count, throw_at);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::vector<GroupValues> sample_rows() {
  return {{0, "color", GroupValueType::Uint8, 3, {1, 2, 3}}, {1, "fa", GroupValueType::Float32, 1, {0, 0, 0, 63}}};
}

TEST(GdatSection, RoundTripsAndRefusesWhatTheSpecificationForbids) {
  const Bytes good = encode_group_values(sample_rows());
  ASSERT_EQ(good.size() % 8, 0u);
  const std::vector<GroupValues> back = decode_group_values(good, 2, throw_at);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(encode_group_values(back), good);
  EXPECT_EQ(decode_error(good, 2), "");

  // Offsets of the first entry: group at 8, dtype at 12, reserved at 14, components at 16, name length at
  // 20, name at 24 ("color", padded to 32), values at 32 (padded to 40).
  EXPECT_NE(decode_error(good, 1).find("names group 1 of 1"), std::string::npos);  // a group that is not there
  auto damaged = [&](std::size_t at, std::uint8_t value) {
    Bytes b = good;
    b[at] = value;
    return b;
  };
  EXPECT_NE(decode_error(damaged(12, 12), 2).find("unknown element type"), std::string::npos);
  EXPECT_NE(decode_error(damaged(14, 1), 2).find("unknown element type"), std::string::npos);  // reserved
  EXPECT_NE(decode_error(damaged(4, 1), 2).find("reserved field"), std::string::npos);
  EXPECT_NE(decode_error(damaged(16, 0), 2).find("0 components"), std::string::npos);
  EXPECT_NE(decode_error(damaged(29, 7), 2).find("name padding is not zero"), std::string::npos);
  EXPECT_NE(decode_error(damaged(35, 7), 2).find("value padding is not zero"), std::string::npos);
  EXPECT_NE(decode_error(damaged(26, '/'), 2).find("without '/' and NUL"), std::string::npos);
  Bytes longer = good;
  longer.resize(good.size() + 8, 0);
  EXPECT_NE(decode_error(longer, 2).find("bytes after its last entry"), std::string::npos);
  EXPECT_NE(decode_error(Bytes(good.begin(), good.end() - 8), 2).find("truncated"), std::string::npos);
  EXPECT_NE(decode_error(damaged(0, 200), 2).find("entry count runs past"), std::string::npos);
  std::vector<GroupValues> twice = sample_rows();
  twice[1].group = 0;
  twice[1].name = "color";
  EXPECT_NE(decode_error(encode_group_values(twice), 2).find("twice"), std::string::npos);
}

TEST(GdatSection, DamageInAFileIsRefusedByOpenNamingTheSection) {
  ScratchDir dir;
  test::write_zip(dir.file("a.trx"), trx_members());
  test::convert_float32(read_trx(dir.file("a.trx")), dir.file("a.vxl"));
  std::uint64_t at = 0;
  {
    const VxlFile f = VxlFile::open(dir.file("a.vxl"));
    at = f.find_section(section_id("GDAT"))->offset;
  }
  std::vector<char> bytes = test::slurp(dir.file("a.vxl"));
  bytes[at + 8] = 9;  // the first entry's group index, past the two groups
  test::write_file(dir.file("a.vxl"), bytes);
  try {
    (void)VxlFile::open(dir.file("a.vxl"));
    ADD_FAILURE() << "a GDAT entry naming group 9 of 2 was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("GDAT entry 0 names group 9 of 2"), std::string::npos) << e.what();
  }
}

TEST(GdatSection, FilesWithoutGroupValuesHaveNoSection) {
  ScratchDir dir;
  auto members = trx_members();
  members.erase(
      std::remove_if(members.begin(), members.end(), [](const auto& m) { return m.first.starts_with("dpg/"); }),
      members.end());
  test::write_zip(dir.file("a.trx"), members);
  const VxlFile f = VxlFile::open(test::convert_float32(read_trx(dir.file("a.trx")), dir.file("a.vxl")));
  EXPECT_EQ(f.find_section(section_id("GDAT")), nullptr);
  EXPECT_TRUE(f.group_values().empty());
  EXPECT_EQ(f.groups().size(), 2u);
}

// The version a file with GDAT carries (spec §10): every file written has streamline lengths (2.4 with packed
// positions or levels, 1.5 otherwise), which holds GDAT too; a package with it is 2.2, one without 2.0, and one of a
// file with levels 2.3 either way (its points shipped level by level).
TEST(GdatSection, AFileWithGroupValuesCarriesTheVersionThatDefinesThem) {
  ScratchDir dir;
  test::write_zip(dir.file("a.trx"), trx_members());
  auto version_of = [](const FileHeader& h) {
    return std::to_string(h.version_major) + "." + std::to_string(h.version_minor);
  };
  auto package_version_of = [](const std::string& path) {
    const std::vector<char> b = test::slurp(path);
    std::uint16_t v[2];
    std::memcpy(v, b.data() + 8, 4);
    return std::to_string(v[0]) + "." + std::to_string(v[1]);
  };
  convert_tractogram(read_trx(dir.file("a.trx")), dir.file("packed.vxl"), ConvertSettings{});
  EXPECT_EQ(version_of(VxlFile::open(dir.file("packed.vxl")).header()), "2.4");
  ConvertSettings plain;
  plain.positions = PositionEncoding::Float32;
  plain.levels = 1;
  convert_tractogram(read_trx(dir.file("a.trx")), dir.file("plain.vxl"), plain);
  EXPECT_EQ(version_of(VxlFile::open(dir.file("plain.vxl")).header()), "1.5");
  pack_vxl(VxlFile::open(dir.file("packed.vxl")), dir.file("a.vxlz"), PackSettings{});
  EXPECT_EQ(package_version_of(dir.file("a.vxlz")), "2.4");  // level order, with a checksum per chunk
  pack_vxl(VxlFile::open(dir.file("plain.vxl")), dir.file("a_plain.vxlz"), PackSettings{});
  EXPECT_EQ(package_version_of(dir.file("a_plain.vxlz")), "2.2");

  auto members = trx_members();
  std::erase_if(members, [](const auto& m) { return m.first.starts_with("dpg/"); });
  test::write_zip(dir.file("b.trx"), members);
  convert_tractogram(read_trx(dir.file("b.trx")), dir.file("b.vxl"), ConvertSettings{});
  EXPECT_EQ(version_of(VxlFile::open(dir.file("b.vxl")).header()), "2.4");
  convert_tractogram(read_trx(dir.file("b.trx")), dir.file("b_plain.vxl"), plain);
  EXPECT_EQ(version_of(VxlFile::open(dir.file("b_plain.vxl")).header()), "1.5");
  pack_vxl(VxlFile::open(dir.file("b.vxl")), dir.file("b.vxlz"), PackSettings{});
  EXPECT_EQ(package_version_of(dir.file("b.vxlz")), "2.4");
  pack_vxl(VxlFile::open(dir.file("b_plain.vxl")), dir.file("b_plain.vxlz"), PackSettings{});
  EXPECT_EQ(package_version_of(dir.file("b_plain.vxlz")), "2.0");
}

// ---- the real fixture: trx-python's small.trx (groups with repeated indices and dpg rows) ----

TEST(TrxGroupValuesReal, TrxPythonSmallKeepsItsRowsAndCountsItsRepeats) {
  VXL_REQUIRE_REAL_DATA();
  ScratchDir dir;
  for (const char* name : {"trx-python__small.trx", "trx-python__small_compressed.trx", "trx-python__small_fldr.trx"}) {
    SCOPED_TRACE(name);
    const Tractogram source = read_trx(test::real(name));
    // groups/CC.int64 lists 34 indices of 29 streamlines, groups/CST_L.int64 14 of 7, CST_R 9 of 7.
    EXPECT_TRUE(has_warning(source.source.warnings,
                            "group CC: 5 duplicate indices collapsed (34 listed in groups/CC.int64, 29 streamlines)"));
    EXPECT_TRUE(
        has_warning(source.source.warnings,
                    "group CST_L: 7 duplicate indices collapsed (14 listed in groups/CST_L.int64, 7 streamlines)"));
    EXPECT_TRUE(
        has_warning(source.source.warnings,
                    "group CST_R: 2 duplicate indices collapsed (9 listed in groups/CST_R.int64, 7 streamlines)"));
    const std::map<std::string, Bytes> rows = rows_by_member(source.groups, source.group_values);
    EXPECT_EQ(rows.size(), 11u);  // CC, AF_L, AF_R: colour, mean FA, volume; CST_L, CST_R: colour
    ASSERT_TRUE(rows.contains("CC/shuffle_colors.3.uint8"));
    EXPECT_EQ(rows.at("CC/shuffle_colors.3.uint8").size(), 3u);
    ASSERT_TRUE(rows.contains("AF_L/mean_fa.1.float16"));
    ASSERT_TRUE(rows.contains("CST_R/shuffle_colors.3.uint8"));

    test::convert_float32(read_trx(test::real(name)), dir.file("s.vxl"));
    pack_vxl(VxlFile::open(dir.file("s.vxl")), dir.file("s.vxlz"), PackSettings{});
    unpack_vxlz(dir.file("s.vxlz"), dir.file("u.vxl"), UnpackSettings{});
    export_trx(VxlFile::open(dir.file("u.vxl")), dir.file("u.trx"));
    const Tractogram back = read_trx(dir.file("u.trx"));
    EXPECT_EQ(rows_by_member(back.groups, back.group_values), rows);
    EXPECT_EQ(members_of(back.groups, "CC"), members_of(source.groups, "CC"));
  }
  const test::CommandResult convert =
      test::run_cli("convert " + q(test::real("trx-python__small.trx")) + " " + q(dir.file("cli.vxl")));
  EXPECT_EQ(convert.exit_code, 0) << convert.output;
  EXPECT_NE(convert.output.find("group CC: 5 duplicate indices collapsed"), std::string::npos) << convert.output;
  EXPECT_NE(convert.output.find("group CST_L: 7 duplicate indices collapsed"), std::string::npos) << convert.output;
}

}  // namespace
}  // namespace vxl
