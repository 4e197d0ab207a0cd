// Groups in exports to formats without groups: a warning naming what a TCK loses, groups as 0/1 cell
// arrays in a VTK (read back as values), one group's TCK (--group) and one TCK per group (--split-groups).
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <numeric>

#include "converter/convert/convert.h"
#include "converter/export/export_groups.h"
#include "converter/export/export_tck.h"
#include "converter/export/export_vtk.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/read_tsf.h"
#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_streamlines.h"
#include "tests/export_test_support.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::q;
using test::ScratchDir;

Tractogram grouped_tractogram() {
  SynthSettings settings;
  settings.streamlines = 300;
  Tractogram t = synthesize_tractogram(settings);
  t.source.path = "grouped.tck";
  t.source.format = "tck";
  std::vector<float> fa(t.point_count());
  for (std::size_t i = 0; i < fa.size(); ++i) fa[i] = 0.25f * static_cast<float>(i % 13);
  t.point_values.push_back({"fa", std::move(fa)});
  t.groups.push_back({"CST_left", {0, 5, 6, 299}});
  t.groups.push_back({"AF right", {1, 5}});
  t.groups.push_back({"a/b", {7}});
  return t;
}

VxlFile grouped_vxl(const ScratchDir& dir) {
  return VxlFile::open(test::convert_float32(grouped_tractogram(), dir.file("g.vxl")));
}

// Streamline s of a tractogram, x,y,z interleaved.
std::vector<float> streamline(const Tractogram& t, std::uint64_t s) {
  return {t.positions.begin() + 3 * t.offsets[s], t.positions.begin() + 3 * t.offsets[s + 1]};
}

// The tractogram's streamlines `members`, in order, bit for bit.
void expect_streamlines(const Tractogram& source, const std::vector<std::uint64_t>& members, const Tractogram& got) {
  ASSERT_EQ(got.streamline_count(), members.size());
  for (std::size_t i = 0; i < members.size(); ++i) EXPECT_EQ(streamline(source, members[i]), streamline(got, i)) << i;
}

const ValueSet* find_set(const std::vector<ValueSet>& sets, const std::string& name) {
  auto it = std::find_if(sets.begin(), sets.end(), [&](const ValueSet& v) { return v.name == name; });
  return it == sets.end() ? nullptr : &*it;
}

TEST(ExportGroups, TckExportWarnsNamingTheGroupsLost) {
  ScratchDir dir;
  const VxlFile f = grouped_vxl(dir);
  const ExportSummary s = export_tck(f, dir.file("g.tck"));
  EXPECT_TRUE(test::has_warning(s.warnings, "3 group(s) not written")) << ::testing::PrintToString(s.warnings);
  EXPECT_TRUE(test::has_warning(s.warnings, "'CST_left' (4 streamlines), 'AF right' (2 streamlines), 'a/b' (1"));
  // A selection holding members of one group only loses that one.
  const StreamlineSubset subset(f.meta().streamline_count, {1, 2});
  const ExportSummary some = export_tck(f, dir.file("s.tck"), {}, &subset);
  EXPECT_TRUE(test::has_warning(some.warnings, "1 group(s) not written: a TCK has no place for them: 'AF right' (1"));
  const auto r = test::run_cli("export " + q(dir.file("g.vxl")) + " " + q(dir.file("c.tck")));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: 3 group(s) not written"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("or each with --split-groups DIR"), std::string::npos) << r.output;
  // `select` has no --group or --split-groups: its warning names only what it has.
  const auto selected = test::run_cli("select " + q(dir.file("g.vxl")) + " " + q(dir.file("s2.tck")) +
                                      " --include box:-1000,-1000,-1000,1000,1000,1000");
  EXPECT_EQ(selected.exit_code, 0) << selected.output;
  EXPECT_NE(selected.output.find("warning: 3 group(s) not written"), std::string::npos) << selected.output;
  EXPECT_NE(selected.output.find("(write them to .trx to keep their groups)"), std::string::npos) << selected.output;
  EXPECT_EQ(selected.output.find("--group"), std::string::npos) << selected.output;
}

TEST(ExportGroups, VtkWritesEachGroupAsACellArrayReadBackAsValues) {
  ScratchDir dir;
  const VxlFile f = grouped_vxl(dir);
  export_vtk(f, dir.file("g.vtk"));
  const Tractogram back = read_vtk(dir.file("g.vtk"));
  std::vector<std::uint64_t> all(300);
  std::iota(all.begin(), all.end(), 0);
  expect_streamlines(grouped_tractogram(), all, back);
  for (const StreamlineGroup& g : grouped_tractogram().groups) {
    const ValueSet* v = find_set(back.streamline_values, g.name);
    ASSERT_NE(v, nullptr) << g.name;
    ASSERT_EQ(v->values.size(), 300u);
    for (std::uint64_t s = 0; s < 300; ++s)
      EXPECT_EQ(v->values[s], std::count(g.members.begin(), g.members.end(), s) ? 1.0f : 0.0f) << g.name << " " << s;
  }
  // A subset keeps each group's members among its streamlines, renumbered.
  const StreamlineSubset subset(f.meta().streamline_count, {4, 5, 7});
  export_vtk(f, dir.file("s.vtk"), &subset);
  const Tractogram some = read_vtk(dir.file("s.vtk"));
  EXPECT_EQ(find_set(some.streamline_values, "CST_left")->values, (std::vector<float>{0, 1, 0}));
  EXPECT_EQ(find_set(some.streamline_values, "AF right")->values, (std::vector<float>{0, 1, 0}));
  EXPECT_EQ(find_set(some.streamline_values, "a/b")->values, (std::vector<float>{0, 0, 1}));
}

TEST(ExportGroups, GroupOptionExportsOnlyThatGroup) {
  ScratchDir dir;
  const VxlFile f = grouped_vxl(dir);
  const std::string vxl = q(dir.file("g.vxl"));
  auto r = test::run_cli("export " + vxl + " " + q(dir.file("cst.tck")) + " --group CST_left --tsf " +
                         q(dir.file("cst.tsf")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("not written"), std::string::npos) << "no group is lost: " << r.output;
  EXPECT_NE(r.output.find("4 streamlines"), std::string::npos) << r.output;
  expect_streamlines(grouped_tractogram(), {0, 5, 6, 299}, read_tck(dir.file("cst.tck")));
  r = test::run_cli("export " + vxl + " " + q(dir.file("af.vtk")) + " --group " + q("AF right"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_streamlines(grouped_tractogram(), {1, 5}, read_vtk(dir.file("af.vtk")));
  r = test::run_cli("export " + vxl + " " + q(dir.file("x.tck")) + " --group nothing");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("has no group 'nothing' (it has 'CST_left', 'AF right', 'a/b')"), std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.tck")));
}

TEST(ExportGroups, SplitGroupsWritesOneTckAndTsfPerGroup) {
  ScratchDir dir;
  grouped_vxl(dir);
  const auto r =
      test::run_cli("export " + q(dir.file("g.vxl")) + " --split-groups " + q(dir.file("groups")) + " --value fa");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Tractogram source = grouped_tractogram();
  for (const auto& [file, members] : std::vector<std::pair<std::string, std::vector<std::uint64_t>>>{
           {"CST_left", {0, 5, 6, 299}}, {"AF right", {1, 5}}, {"a_b", {7}}}) {
    const std::string tck = dir.file("groups/" + file + ".tck");
    expect_streamlines(source, members, read_tck(tck));
    Tractogram with_values = read_tck(tck);
    attach_tsf(with_values, dir.file("groups/" + file + ".tsf"));
    ASSERT_EQ(with_values.point_values.size(), 1u);
    std::vector<float> expected;
    for (std::uint64_t s : members)
      expected.insert(expected.end(), source.point_values[0].values.begin() + source.offsets[s],
                      source.point_values[0].values.begin() + source.offsets[s + 1]);
    EXPECT_EQ(with_values.point_values[0].values, expected) << file;
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.file("groups")), {}), 6);
  // Without groups, or with an output file as well: usage.
  EXPECT_EQ(test::run_cli("export " + q(dir.file("g.vxl")) + " " + q(dir.file("o.tck")) + " --split-groups " +
                          q(dir.file("groups")))
                .exit_code,
            2);
}

TEST(ExportGroups, FileNamesAreSafeAndUnique) {
  const std::vector<StreamlineGroup> groups = {{"a/b", {}}, {"a_b", {}},  {"..", {}},
                                               {"A_B", {}}, {"x\ny", {}}, {"", {}}};
  EXPECT_EQ(group_file_names(groups), (std::vector<std::string>{"a_b", "a_b_2", "_..", "A_B_3", "x_y", "_"}));
  // Names longer than a file system holds are cut at a character's start, and stay unique: two names of 300
  // characters that differ only at their end, of two-byte characters from byte 199 on.
  std::string first = std::string(199, 'a'), second;
  for (int i = 0; i < 100; ++i) first += "\xC3\xA9";  // é
  second = first + "x";
  first += "y";
  const std::vector<std::string> cut = group_file_names({{first, {}}, {second, {}}});
  ASSERT_EQ(cut.size(), 2u);
  EXPECT_EQ(cut[0], std::string(199, 'a'));  // byte 199 starts an é that does not fit in 200 bytes
  EXPECT_EQ(cut[1], std::string(199, 'a') + "_2");
}

// A group named longer than a file name may be: every group's file is written, that one's too (not exit 5
// with the others written).
TEST(ExportGroups, SplitGroupsWritesAGroupWithAVeryLongName) {
  ScratchDir dir;
  Tractogram t = grouped_tractogram();
  t.groups.push_back({std::string(300, 'L'), {2, 3}});
  ConvertSettings s;
  convert_tractogram(std::move(t), dir.file("long.vxl"), s);
  const auto r = test::run_cli("export " + q(dir.file("long.vxl")) + " --split-groups " + q(dir.file("groups")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("groups/" + std::string(kMaxGroupFileNameBytes, 'L') + ".tck")));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.file("groups")), {}), 4);
}

}  // namespace
}  // namespace vxl
