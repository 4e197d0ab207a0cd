// Export back to the community's formats: TRX read back by our reader (positions, offsets, groups
// identical to the .vxl's streamlines) and checked by an independent reader (Python's zipfile and numpy)
// against the TRX specification's structure; TCK read back by our reader identically.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "converter/convert/convert.h"
#include "converter/export/export_tck.h"
#include "converter/export/export_trx.h"
#include "converter/readers/read_tractogram.h"
#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_streamlines.h"
#include "tests/export_test_support.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;

Tractogram trx_grouped_tractogram() {
  SynthSettings settings;
  settings.streamlines = 400;
  Tractogram t = synthesize_tractogram(settings);
  t.source.path = "grouped.tck";
  t.source.format = "tck";
  const float jump[6] = {0, 0, 0, 40, 1, 1};  // synthetic face points, which export drops
  t.add_streamline(jump, 2);
  t.add_streamline(jump, 0);
  t.groups.push_back({"CST_left", {0, 5, 6, 400}});
  t.groups.push_back({"AF right", {1, 401}});
  return t;
}

// The .vxl's streamlines as a tractogram (what any export must give back).
Tractogram streamlines_of(const VxlFile& f) {
  Tractogram t;
  walk_streamlines(
      f, {[&](std::uint64_t, std::span<const float> xyz) { t.add_streamline(xyz.data(), xyz.size() / 3); }, {}, {}});
  return t;
}

void expect_same_streamlines(const Tractogram& expected, const Tractogram& got) {
  EXPECT_EQ(expected.offsets, got.offsets);
  ASSERT_EQ(expected.positions.size(), got.positions.size());
  if (!expected.positions.empty()) {
    EXPECT_EQ(std::memcmp(expected.positions.data(), got.positions.data(), expected.positions.size() * sizeof(float)),
              0)
        << "positions must be bit-identical";
  }
}

// An independent structural check of a TRX archive against the specification, in Python (zipfile +
// numpy, no TRX library): stored members, header keys, array names and dtypes, offsets N + 1 with the
// sentinel, positions 3 * NB_VERTICES float32, groups unsigned, increasing and below N, dpv / dps
// float32 with one row per point / streamline, dpg one row per existing group.
constexpr const char* kTrxCheck = R"PY(
import json, sys, zipfile
import numpy as np
z = zipfile.ZipFile(sys.argv[1])
names = set(z.namelist())
for info in z.infolist():
    assert info.compress_type == zipfile.ZIP_STORED, info.filename + " is compressed"
header = json.loads(z.read("header.json"))
for key in ("DIMENSIONS", "VOXEL_TO_RASMM", "NB_STREAMLINES", "NB_VERTICES"):
    assert key in header, "header.json lacks " + key
dims = header["DIMENSIONS"]
assert len(dims) == 3 and all(isinstance(d, int) and d > 0 for d in dims), dims
assert np.array(header["VOXEL_TO_RASMM"], dtype=float).shape == (4, 4)
n, v = header["NB_STREAMLINES"], header["NB_VERTICES"]
def dtype_of(name):
    return np.dtype(name.rsplit(".", 1)[1]).newbyteorder("<")
positions = [m for m in names if m.startswith("positions.")]
offsets = [m for m in names if m.startswith("offsets.")]
assert positions == ["positions.3.float32"], positions
assert offsets == ["offsets.uint64"], offsets
raw = z.read(positions[0])
assert len(raw) == 3 * v * 4, (len(raw), v)
p = np.frombuffer(raw, dtype=dtype_of(positions[0])).reshape(-1, 3)
assert p.shape == (v, 3) and np.all(np.isfinite(p))
o = np.frombuffer(z.read(offsets[0]), dtype=dtype_of(offsets[0]))
assert o.size == n + 1, (o.size, n)
assert o[0] == 0 and o[-1] == v and np.all(np.diff(o.astype(np.int64)) >= 0)
groups = sorted(m for m in names if m.startswith("groups/"))
for g in groups:
    dt = dtype_of(g)
    assert dt == np.dtype("<u4"), g
    a = np.frombuffer(z.read(g), dtype=dt)
    assert np.all(a < n) and np.all(np.diff(a.astype(np.int64)) > 0), g
values = sorted(m for m in names if m.startswith("dpv/") or m.startswith("dps/"))
for m in values:
    parts = m.split("/", 1)[1].split(".")
    width = int(parts[-2]) if len(parts) == 3 else 1
    assert len(parts) in (2, 3) and parts[-1] == "float32" and width >= 1, m
    assert len(z.read(m)) == (v if m.startswith("dpv/") else n) * width * 4, m
group_names = set(g[len("groups/"):].rsplit(".", 1)[0] for g in groups)
rows = sorted(m for m in names if m.startswith("dpg/"))
for m in rows:
    _, group, file = m.split("/")
    parts = file.split(".")
    width = int(parts[-2]) if len(parts) >= 3 and parts[-2].isdigit() else 1
    assert group in group_names and width >= 1, m
    assert len(z.read(m)) == width * np.dtype(parts[-1]).itemsize, m
assert names == set(positions + offsets + groups + values + rows + ["header.json"]), names
print("TRX-OK", n, v, "|".join(g[len("groups/"):].rsplit(".", 1)[0] for g in groups))
)PY";

std::string check_trx_in_python(const ScratchDir& dir, const std::string& trx) {
  const std::string script = dir.file("check_trx.py");
  std::ofstream(script) << kTrxCheck;
  return test::run_program("/usr/bin/python3", "'" + script + "' '" + trx + "'").output;
}

bool have_python_numpy() { return test::run_program("/usr/bin/python3", "-c 'import numpy'").exit_code == 0; }

TEST(ExportTrx, ReadsBackIdenticallyWithGroups) {
  ScratchDir dir;
  const VxlFile f = VxlFile::open(test::convert_float32(trx_grouped_tractogram(), dir.file("g.vxl")));
  ASSERT_GT(f.meta().synthetic_point_count, 0u);
  export_trx(f, dir.file("g.trx"));
  const Tractogram back = read_trx(dir.file("g.trx"));
  expect_same_streamlines(streamlines_of(f), back);
  expect_same_streamlines(trx_grouped_tractogram(), back);
  ASSERT_EQ(back.groups.size(), 2u);
  // Member names are listed in archive order; compare as a set.
  for (const StreamlineGroup& expected : trx_grouped_tractogram().groups) {
    auto it =
        std::find_if(back.groups.begin(), back.groups.end(), [&](const auto& g) { return g.name == expected.name; });
    ASSERT_NE(it, back.groups.end()) << expected.name;
    EXPECT_EQ(it->members, expected.members);
  }
  EXPECT_EQ(back.source.dtype, "float32");
  EXPECT_TRUE(back.source.warnings.empty());
}

TEST(ExportTrx, StructureFollowsTheSpecificationInAnIndependentReader) {
  if (!have_python_numpy()) GTEST_SKIP() << "/usr/bin/python3 with numpy is needed for the independent check";
  ScratchDir dir;
  const VxlFile f = VxlFile::open(test::convert_float32(trx_grouped_tractogram(), dir.file("g.vxl")));
  export_trx(f, dir.file("g.trx"));
  const std::string out = check_trx_in_python(dir, dir.file("g.trx"));
  EXPECT_NE(out.find("TRX-OK 402 " + std::to_string(f.meta().point_count) + " AF right|CST_left"), std::string::npos)
      << out;
}

TEST(ExportTrx, EmptyTractogram) {
  ScratchDir dir;
  Tractogram t;
  t.source.path = "empty.tck";
  const VxlFile f = VxlFile::open(test::convert_float32(std::move(t), dir.file("e.vxl")));
  export_trx(f, dir.file("e.trx"));
  const Tractogram back = read_trx(dir.file("e.trx"));
  EXPECT_EQ(back.streamline_count(), 0u);
  if (have_python_numpy()) {
    EXPECT_NE(check_trx_in_python(dir, dir.file("e.trx")).find("TRX-OK 0 0"), std::string::npos);
  }
}

TEST(ExportTrx, DefaultReferenceCoversTheBounds) {
  ScratchDir dir;
  const VxlFile f = VxlFile::open(test::convert_float32(trx_grouped_tractogram(), dir.file("g.vxl")));
  const TrxReference r = trx_reference(f);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(r.voxel_to_rasmm[c][c], 1.0);
    EXPECT_EQ(r.voxel_to_rasmm[c][3], std::floor(f.meta().bounds_min[c]));
    // Every point's voxel index (rounded to the nearest centre) lies inside DIMENSIONS.
    EXPECT_LT(std::lround(f.meta().bounds_max[c] - r.voxel_to_rasmm[c][3]), r.dimensions[c]);
  }
}

TEST(ExportTrx, GroupNameThatCannotBeAMemberIsUnsupported) {
  ScratchDir dir;
  Tractogram t = trx_grouped_tractogram();
  t.groups.push_back({"a/b", {2}});
  const VxlFile f = VxlFile::open(test::convert_float32(std::move(t), dir.file("g.vxl")));
  try {
    export_trx(f, dir.file("g.trx"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("g.trx")));
}

TEST(ExportTrx, CliChoosesTheFormatByExtension) {
  ScratchDir dir;
  const std::string vxl = test::convert_float32(trx_grouped_tractogram(), dir.file("g.vxl"));
  auto r = test::run_cli("export '" + vxl + "' '" + dir.file("g.TRX") + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_trx(dir.file("g.TRX")).streamline_count(), 402u);
  r = test::run_cli("export '" + vxl + "' '" + dir.file("g.tck") + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_tck(dir.file("g.tck")).streamline_count(), 402u);
  r = test::run_cli("export '" + vxl + "' '" + dir.file("g.vtu") + "'");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("g.vtu")));
}

TEST(ExportTrxReal, SourceReferenceAndGroupsAreKept) {
  VXL_REQUIRE_REAL_DATA();
  ScratchDir dir;
  const std::string afq = "niivue__sub-01_ses-01_dwi_space-RASMM_model-probCSD_algo-AFQ_tractography.trx";
  const Tractogram source = read_trx(test::real(afq));
  const VxlFile f = VxlFile::open(test::convert_float32(read_trx(test::real(afq)), dir.file("afq.vxl")));
  export_trx(f, dir.file("afq.trx"));
  const Tractogram back = read_trx(dir.file("afq.trx"));
  expect_same_streamlines(streamlines_of(f), back);
  EXPECT_EQ(back.source.header["DIMENSIONS"], source.source.header["DIMENSIONS"]);
  ASSERT_TRUE(back.source.vox_to_ras && source.source.vox_to_ras);
  EXPECT_EQ(*back.source.vox_to_ras, *source.source.vox_to_ras);
  ASSERT_EQ(back.groups.size(), source.groups.size());
  for (std::size_t g = 0; g < source.groups.size(); ++g) {
    EXPECT_EQ(back.groups[g].name, source.groups[g].name);
    EXPECT_EQ(back.groups[g].members, source.groups[g].members);
  }
  if (have_python_numpy()) {
    EXPECT_NE(check_trx_in_python(dir, dir.file("afq.trx")).find("TRX-OK 508 141447 ARC_L|ARC_R"), std::string::npos);
  }

  // A TRK source gives its dim and vox_to_ras.
  const Tractogram trk = read_trk(test::real("nibabel__standard.trk"));
  const VxlFile g =
      VxlFile::open(test::convert_float32(read_trk(test::real("nibabel__standard.trk")), dir.file("trk.vxl")));
  const TrxReference r = trx_reference(g);
  ASSERT_TRUE(trk.source.vox_to_ras);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_EQ(r.voxel_to_rasmm[i][j], (*trk.source.vox_to_ras)[4 * i + j]);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(r.dimensions[c], trk.source.header["dim"][c].get<std::int64_t>());
}

TEST(ExportTrxReal, TckAndTrxOfRealFixturesReadBackIdentically) {
  VXL_REQUIRE_REAL_DATA();
  ScratchDir dir;
  for (const char* name : {"TractographyFormat__stroke.tck", "trx-python__small.trx", "niivue__C_PHP.trk.gz",
                           "nibabel__empty.tck", "mrtrix3__tmp.tck"}) {
    SCOPED_TRACE(name);
    const VxlFile f = VxlFile::open(test::convert_float32(read_tractogram(test::real(name)), dir.file("r.vxl")));
    const Tractogram expected = streamlines_of(f);
    export_tck(f, dir.file("r.tck"));
    expect_same_streamlines(expected, read_tck(dir.file("r.tck")));
    export_trx(f, dir.file("r.trx"));
    expect_same_streamlines(expected, read_trx(dir.file("r.trx")));
    if (have_python_numpy()) {
      EXPECT_NE(check_trx_in_python(dir, dir.file("r.trx")).find("TRX-OK"), std::string::npos);
    }
  }
}

}  // namespace
}  // namespace vxl
