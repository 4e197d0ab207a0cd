// Tests of the TRX reader: every real TRX fixture (zip and directory), reference points from an
// independent Python reader, pairs that must agree, groups, and small synthetic TRX files, valid and
// broken, written to a scratch directory (as directories, or as zips made by a minimal stored-zip
// writer below, so the tests do not depend on libzip for writing).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "converter/readers/float16.h"
#include "converter/readers/read_tractogram.h"
#include "format/base/checksum.h"
#include "format/base/error.h"
#include "tests/test_support.h"
#include "tests/zip_writer.h"

namespace {

using vxl::test::has_warning;
using vxl::test::real;

struct TrxCounts {
  const char* file;
  std::uint64_t streamlines;
  std::uint64_t points;
  const char* dtype;
};

// The counts the fixtures' upstream projects publish, except niivue__dpsv.trx: the published count copies header.json's
// NB_STREAMLINES (459), but its offsets hold 460 streamline starts and no sentinel (the last entry,
// 95708, is below NB_VERTICES = 95865); the data is the same 460 streamlines as the older
// niivue__tests__dpsv.trx and niivue__C_PHP.trk.gz, whose last streamline has 157 points.
const TrxCounts kTrxFixtures[] = {
    {"niivue__sub-01_ses-01_dwi_space-RASMM_model-probCSD_algo-AFQ_tractography.trx", 508, 141447, "float32"},
    {"niivue__dpsv.trx", 460, 95865, "float16"},
    {"niivue__tests__dpsv.trx", 460, 95865, "float16"},
    {"niivue__dps.trx", 460, 95865, "float16"},
    {"niivue__colby.trx", 2, 32, "float16"},
    {"trx-javascript__gs.trx", 13, 104, "float32"},
    {"trx-python__small.trx", 1000, 33886, "float16"},
    {"trx-python__small_compressed.trx", 1000, 33886, "float16"},
    {"trx-python__small_fldr.trx", 1000, 33886, "float16"},
};

TEST(ReadTrx, EveryFixtureHasTheDocumentedCounts) {
  VXL_REQUIRE_REAL_DATA();
  for (const auto& f : kTrxFixtures) {
    SCOPED_TRACE(f.file);
    const vxl::Tractogram t = vxl::read_trx(real(f.file));
    EXPECT_EQ(t.streamline_count(), f.streamlines);
    EXPECT_EQ(t.point_count(), f.points);
    EXPECT_EQ(t.offsets.front(), 0u);
    EXPECT_EQ(t.offsets.back(), t.point_count());
    EXPECT_EQ(t.source.format, "trx");
    EXPECT_EQ(t.source.dtype, f.dtype);
    EXPECT_EQ(t.source.xxh3_128.size(), 32u);
    EXPECT_TRUE(t.source.vox_to_ras.has_value());
    EXPECT_TRUE(t.source.header.contains("_members"));
    EXPECT_NO_THROW((void)t.source.header.dump());
    // Only the mislabelled dpsv.trx and trx-python's small set (repeated group indices) deserve warnings.
    if (std::string(f.file) == "niivue__dpsv.trx") {
      EXPECT_TRUE(has_warning(t.source.warnings, "NB_STREAMLINES = 459"));
      EXPECT_EQ(t.source.warnings.size(), 1u);
    } else if (std::string(f.file).starts_with("trx-python__small")) {
      EXPECT_EQ(t.source.warnings.size(), 3u);  // groups CC, CST_L and CST_R
      EXPECT_TRUE(has_warning(t.source.warnings, "duplicate indices collapsed"));
    } else {
      EXPECT_TRUE(t.source.warnings.empty()) << t.source.warnings.front();
    }
  }
}

// Reference values: an independent reader (zipfile + numpy), run in the real-data folder as
//   /usr/bin/python3 -c "import zipfile, json, numpy as np; z =
//   zipfile.ZipFile('niivue__sub-01_ses-01_dwi_space-RASMM_model-probCSD_algo-AFQ_tractography.trx'); h =
//   json.loads(z.read('header.json')); p = np.frombuffer(z.read('positions.3.float32'), '<f4').reshape(-1, 3); o =
//   np.frombuffer(z.read('offsets.uint32'), '<u4'); print(len(o) - 1, o[-1] == h['NB_VERTICES'], p[o[0]:o[0] +
//   2].tolist(), p[o[-1] - 1].tolist())"
// which printed
//   508 True [[14.211463928222656, 32.482147216796875, 46.71699523925781],
//   [14.213859558105469, 32.21466064453125, 46.29457092285156]] [-55.147674560546875,
//   -57.2192497253418, 5.0831146240234375]
// float32 positions are copied bit-exactly, so these compare with ==.
TEST(ReadTrx, AfqMatchesIndependentReaderExactly) {
  VXL_REQUIRE_REAL_DATA();
  const vxl::Tractogram t =
      vxl::read_trx(real("niivue__sub-01_ses-01_dwi_space-RASMM_model-probCSD_algo-AFQ_tractography.trx"));
  const std::vector<float> first(t.positions.begin(), t.positions.begin() + 6);
  EXPECT_EQ(first, (std::vector<float>{14.211463928222656f, 32.482147216796875f, 46.71699523925781f,
                                       14.213859558105469f, 32.21466064453125f, 46.29457092285156f}));
  const std::vector<float> last(t.positions.end() - 3, t.positions.end());
  EXPECT_EQ(last, (std::vector<float>{-55.147674560546875f, -57.2192497253418f, 5.0831146240234375f}));
  EXPECT_EQ(t.source.bytes, 1702188u);
  EXPECT_EQ(t.source.header["NB_STREAMLINES"], 508);
  ASSERT_TRUE(t.source.vox_to_ras.has_value());
  EXPECT_EQ((*t.source.vox_to_ras)[0], 2.0);
  EXPECT_EQ((*t.source.vox_to_ras)[3], -80.0);
}

TEST(ReadTrx, AfqHasGroupsArcLAndArcR) {
  VXL_REQUIRE_REAL_DATA();
  const vxl::Tractogram t =
      vxl::read_trx(real("niivue__sub-01_ses-01_dwi_space-RASMM_model-probCSD_algo-AFQ_tractography.trx"));
  ASSERT_EQ(t.groups.size(), 2u);
  EXPECT_EQ(t.groups[0].name, "ARC_L");
  EXPECT_EQ(t.groups[1].name, "ARC_R");
  // groups/ARC_L.uint32 is 1944 bytes (486 indices) and ARC_R 88 bytes (22), starting 22.. and 0..
  EXPECT_EQ(t.groups[0].members.size(), 486u);
  EXPECT_EQ(t.groups[1].members.size(), 22u);
  EXPECT_EQ(t.groups[0].members.front(), 22u);
  EXPECT_EQ(t.groups[1].members.front(), 0u);
  for (const auto& g : t.groups) {
    for (std::size_t i = 1; i < g.members.size(); ++i) EXPECT_LT(g.members[i - 1], g.members[i]);
    EXPECT_LT(g.members.back(), t.streamline_count());
  }
}

TEST(ReadTrx, DpsvSentinelAndNoSentinelFilesAgree) {
  VXL_REQUIRE_REAL_DATA();
  const vxl::Tractogram a = vxl::read_trx(real("niivue__dpsv.trx"));         // 460 uint32 entries
  const vxl::Tractogram b = vxl::read_trx(real("niivue__tests__dpsv.trx"));  // 460 uint64 entries
  const vxl::Tractogram c = vxl::read_trx(real("niivue__dps.trx"));
  EXPECT_EQ(a.offsets, b.offsets);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(b.offsets, c.offsets);
  EXPECT_EQ(b.positions, c.positions);
  // The same streamlines as the TRK version: same per-streamline point counts.
  const vxl::Tractogram trk = vxl::read_trk(real("niivue__C_PHP.trk.gz"));
  EXPECT_EQ(trk.offsets, a.offsets);
}

TEST(ReadTrx, TrxPythonZipCompressedZipAndDirectoryAgree) {
  VXL_REQUIRE_REAL_DATA();
  const vxl::Tractogram stored = vxl::read_trx(real("trx-python__small.trx"));
  const vxl::Tractogram deflated = vxl::read_trx(real("trx-python__small_compressed.trx"));
  const vxl::Tractogram dir = vxl::read_trx(real("trx-python__small_fldr.trx"));
  for (const vxl::Tractogram* t : {&deflated, &dir}) {
    EXPECT_EQ(t->offsets, stored.offsets);
    EXPECT_EQ(t->positions, stored.positions);
    ASSERT_EQ(t->groups.size(), stored.groups.size());
    for (std::size_t i = 0; i < stored.groups.size(); ++i) {
      EXPECT_EQ(t->groups[i].name, stored.groups[i].name);
      EXPECT_EQ(t->groups[i].members, stored.groups[i].members);
    }
    EXPECT_EQ(t->source.header["_members"], stored.source.header["_members"]);
  }
  ASSERT_EQ(stored.groups.size(), 5u);  // AF_L, AF_R, CC, CST_L, CST_R (int64 indices)
  EXPECT_EQ(stored.groups[0].name, "AF_L");
  EXPECT_EQ(stored.groups[2].name, "CC");
  // groups/CC.int64 holds 34 unsorted indices with 5 repeats (e.g. 260, 260), CST_L 14 with 7, CST_R 9 with 2:
  // members come back sorted and deduplicated, with a warning per group.
  EXPECT_EQ(stored.groups[2].members.size(), 29u);
  EXPECT_EQ(stored.groups[2].members.front(), 127u);
  EXPECT_EQ(stored.groups[2].members.back(), 964u);
  EXPECT_EQ(stored.groups[3].members, (std::vector<std::uint64_t>{342, 359, 444, 489, 501, 781, 957}));
  EXPECT_TRUE(vxl::test::has_warning(stored.source.warnings, "group CC: 5 duplicate indices collapsed (34 listed"));
  EXPECT_TRUE(vxl::test::has_warning(stored.source.warnings, "group CST_L: 7 duplicate indices collapsed (14 listed"));
  // Directory provenance: 391495 bytes of member files (the fixture's published size).
  EXPECT_EQ(dir.source.bytes, 391495u);
  EXPECT_EQ(stored.source.bytes, 394709u);
  EXPECT_NE(dir.source.xxh3_128, stored.source.xxh3_128);
}

TEST(ReadTrx, ColbyTrxIsColbyTrkAtFloat16Precision) {
  VXL_REQUIRE_REAL_DATA();
  const vxl::Tractogram trx = vxl::read_trx(real("niivue__colby.trx"));
  const vxl::Tractogram trk = vxl::read_trk(real("niivue__colby.trk"));
  ASSERT_EQ(trx.offsets, trk.offsets);
  for (std::size_t i = 0; i < trx.positions.size(); ++i)  // float16 spacing is 0.125 at 128..256
    EXPECT_NEAR(trx.positions[i], trk.positions[i], 0.0625) << i;
}

TEST(Float16, ConvertsExactly) {
  EXPECT_EQ(vxl::half_to_float(0x3C00), 1.0f);
  EXPECT_EQ(vxl::half_to_float(0xC000), -2.0f);
  EXPECT_EQ(vxl::half_to_float(0x7BFF), 65504.0f);
  EXPECT_EQ(vxl::half_to_float(0x3555), 0.333251953125f);
  EXPECT_EQ(vxl::half_to_float(0x0001), std::ldexp(1.0f, -24));         // smallest subnormal
  EXPECT_EQ(vxl::half_to_float(0x03FF), 1023 * std::ldexp(1.0f, -24));  // largest subnormal
  EXPECT_EQ(vxl::half_to_float(0x0400), std::ldexp(1.0f, -14));         // smallest normal
  EXPECT_EQ(vxl::half_to_float(0x0000), 0.0f);
  EXPECT_TRUE(std::signbit(vxl::half_to_float(0x8000)));
  EXPECT_EQ(vxl::half_to_float(0x7C00), std::numeric_limits<float>::infinity());
  EXPECT_EQ(vxl::half_to_float(0xFC00), -std::numeric_limits<float>::infinity());
  EXPECT_TRUE(std::isnan(vxl::half_to_float(0x7E00)));
  // Every finite half round-trips through float -> double -> the half's exact value.
  for (std::uint32_t h = 0; h < 0x10000; ++h) {
    const std::uint32_t e = (h >> 10) & 0x1F, m = h & 0x3FF;
    if (e == 0x1F) continue;
    const double mag = e == 0 ? std::ldexp(double(m), -24) : std::ldexp(1024.0 + m, int(e) - 25);
    ASSERT_EQ(double(vxl::half_to_float(static_cast<std::uint16_t>(h))), (h & 0x8000) ? -mag : mag) << h;
  }
}

// ---- synthetic TRX ----

using vxl::test::Bytes;

template <typename T>
Bytes le_bytes(const std::vector<T>& values) {
  Bytes out(values.size() * sizeof(T));
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint64_t u = 0;
    std::memcpy(&u, &values[i], sizeof(T));
    for (std::size_t b = 0; b < sizeof(T); ++b) out[i * sizeof(T) + b] = static_cast<std::uint8_t>(u >> (8 * b));
  }
  return out;
}

Bytes text(const std::string& s) { return Bytes(s.begin(), s.end()); }

using vxl::test::write_zip;

using vxl::test::write_dir;

std::string header_json(int n, int v) {
  return "{\"DIMENSIONS\": [10, 10, 10], \"VOXEL_TO_RASMM\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "
         "\"NB_STREAMLINES\": " +
         std::to_string(n) + ", \"NB_VERTICES\": " + std::to_string(v) + "}";
}

// 3 streamlines of 2, 1 and 3 points.
const std::vector<float> kPositions = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17};
const std::vector<std::uint64_t> kOffsets = {0, 2, 3, 6};

std::vector<std::pair<std::string, Bytes>> valid_members() {
  return {{"header.json", text(header_json(3, 6))},
          {"positions.3.float32", le_bytes(kPositions)},
          {"offsets.uint32", le_bytes(std::vector<std::uint32_t>{0, 2, 3, 6})},
          {"dps/weight.float32", le_bytes(std::vector<float>{1, 2, 3})},
          {"groups/b.int16", le_bytes(std::vector<std::int16_t>{2, 0, 2})},
          {"groups/a.uint8", le_bytes(std::vector<std::uint8_t>{1})}};
}

void replace(std::vector<std::pair<std::string, Bytes>>& members, const std::string& name, const std::string& new_name,
             Bytes data) {
  for (auto& m : members)
    if (m.first == name) m = {new_name, std::move(data)};
}

void expect_input_error(const std::string& path, const std::string& part) {
  try {
    (void)vxl::read_trx(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const vxl::Error& e) {
    const std::string msg = e.what();
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << msg;
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(part), std::string::npos) << msg;
  }
}

TEST(ReadTrxSynthetic, ZipAndDirectoryAndBothOffsetConventions) {
  vxl::test::ScratchDir dir;
  auto members = valid_members();
  write_zip(dir.file("a.trx"), members);
  write_dir(dir.file("a_dir.trx"), members);
  replace(members, "offsets.uint32", "offsets.uint64", le_bytes(std::vector<std::uint64_t>{0, 2, 3}));
  write_zip(dir.file("no_sentinel.trx"), members);
  for (const char* name : {"a.trx", "a_dir.trx", "no_sentinel.trx"}) {
    SCOPED_TRACE(name);
    const vxl::Tractogram t = vxl::read_trx(dir.file(name));
    EXPECT_EQ(t.positions, kPositions);
    EXPECT_EQ(t.offsets, kOffsets);
    // groups/b.int16 lists 2 twice: the one warning.
    EXPECT_EQ(t.source.warnings,
              (std::vector<std::string>{
                  "group b: 1 duplicate indices collapsed (3 listed in groups/b.int16, 2 streamlines)"}));
    ASSERT_EQ(t.groups.size(), 2u);
    EXPECT_EQ(t.groups[0].name, "a");
    EXPECT_EQ(t.groups[0].members, (std::vector<std::uint64_t>{1}));
    EXPECT_EQ(t.groups[1].name, "b");
    EXPECT_EQ(t.groups[1].members, (std::vector<std::uint64_t>{0, 2}));  // sorted, deduplicated
    EXPECT_EQ(t.source.dtype, "float32");
  }
}

TEST(ReadTrxSynthetic, DirectoryProvenanceHashesMembersInSortedPathOrder) {
  vxl::test::ScratchDir dir;
  const auto members = valid_members();
  write_dir(dir.file("d.trx"), members);
  const vxl::Tractogram t = vxl::read_trx(dir.file("d.trx"));
  // dps/weight.float32 < groups/a.uint8 < groups/b.int16 < header.json < offsets.uint32 < positions.3.float32
  std::vector<std::pair<std::string, Bytes>> sorted = members;
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  Bytes all;
  std::uint64_t total = 0;
  for (const auto& [name, data] : sorted) {
    all.insert(all.end(), data.begin(), data.end());
    total += data.size();
  }
  EXPECT_EQ(t.source.bytes, total);
  EXPECT_EQ(t.source.xxh3_128, vxl::xxh3_128_hex(all.data(), all.size()));
  const vxl::Tractogram again = vxl::read_trx(dir.file("d.trx"));
  EXPECT_EQ(again.source.xxh3_128, t.source.xxh3_128);
  std::ofstream(dir.file("d.trx/dps/weight.float32"), std::ios::binary | std::ios::app).put(0);
  EXPECT_NE(vxl::read_trx(dir.file("d.trx")).source.xxh3_128, t.source.xxh3_128);
}

TEST(ReadTrxSynthetic, Float16AndFloat64Positions) {
  vxl::test::ScratchDir dir;
  auto members = valid_members();
  std::vector<std::uint16_t> halves = {0x3C00, 0xC000, 0x3555, 0,      0x8000, 0x7BFF, 0x0001, 0x3800, 0x4000,
                                       0x4200, 0x4400, 0x4500, 0x4600, 0x4700, 0x4800, 0x4880, 0x4900, 0x4980};
  replace(members, "positions.3.float32", "positions.3.float16", le_bytes(halves));
  write_zip(dir.file("h.trx"), members);
  const vxl::Tractogram h = vxl::read_trx(dir.file("h.trx"));
  EXPECT_EQ(h.source.dtype, "float16");
  ASSERT_EQ(h.positions.size(), 18u);
  EXPECT_EQ(h.positions[0], 1.0f);
  EXPECT_EQ(h.positions[1], -2.0f);
  EXPECT_EQ(h.positions[2], 0.333251953125f);
  EXPECT_EQ(h.positions[5], 65504.0f);
  EXPECT_EQ(h.positions[6], std::ldexp(1.0f, -24));

  std::vector<double> doubles(18);
  for (int i = 0; i < 18; ++i) doubles[i] = 0.1 * i;
  replace(members, "positions.3.float16", "positions.3.float64", le_bytes(doubles));
  write_zip(dir.file("d.trx"), members);
  const vxl::Tractogram d = vxl::read_trx(dir.file("d.trx"));
  EXPECT_EQ(d.source.dtype, "float64");
  for (int i = 0; i < 18; ++i) EXPECT_EQ(d.positions[i], static_cast<float>(0.1 * i));
  EXPECT_TRUE(has_warning(d.source.warnings, "float64 positions rounded to float32"));
  EXPECT_EQ(d.source.warnings.size(), 2u);  // and group b's repeated index
}

TEST(ReadTrxBroken, ZipMissingHeaderJson) {
  vxl::test::ScratchDir dir;
  auto members = valid_members();
  members.erase(members.begin());
  write_zip(dir.file("nohdr.trx"), members);
  expect_input_error(dir.file("nohdr.trx"), "header.json");
}

TEST(ReadTrxBroken, OffsetsPointingPastPositions) {
  vxl::test::ScratchDir dir;
  auto members = valid_members();
  replace(members, "offsets.uint32", "offsets.uint32", le_bytes(std::vector<std::uint32_t>{0, 2, 9}));
  write_zip(dir.file("past.trx"), members);
  expect_input_error(dir.file("past.trx"), "offsets.uint32: entry 2 (9) points past the 6 vertices");
  replace(members, "offsets.uint32", "offsets.uint32", le_bytes(std::vector<std::uint32_t>{0, 2, 3, 7}));
  write_zip(dir.file("past_sentinel.trx"), members);
  expect_input_error(dir.file("past_sentinel.trx"), "offsets.uint32: the last entry (7) points past");
}

TEST(ReadTrxBroken, NonMonotonicOffsets) {
  vxl::test::ScratchDir dir;
  auto members = valid_members();
  replace(members, "offsets.uint32", "offsets.uint32", le_bytes(std::vector<std::uint32_t>{0, 3, 2, 6}));
  write_zip(dir.file("dec.trx"), members);
  expect_input_error(dir.file("dec.trx"), "offsets.uint32: offsets decrease at entry 2");
  replace(members, "offsets.uint32", "offsets.uint32", le_bytes(std::vector<std::uint32_t>{1, 2, 3, 6}));
  write_dir(dir.file("start.trx"), members);
  expect_input_error(dir.file("start.trx"), "offsets.uint32: the first offset is 1");
}

TEST(ReadTrxBroken, InconsistentSizesAndNames) {
  vxl::test::ScratchDir dir;
  {
    auto m = valid_members();
    replace(m, "offsets.uint32", "offsets.uint32", le_bytes(std::vector<std::uint32_t>{0, 2}));
    write_zip(dir.file("count.trx"), m);
    expect_input_error(dir.file("count.trx"), "offsets.uint32: has 2 entries");
  }
  {
    auto m = valid_members();
    replace(m, "positions.3.float32", "positions.3.float32", le_bytes(std::vector<float>{1, 2, 3}));
    write_zip(dir.file("pos.trx"), m);
    expect_input_error(dir.file("pos.trx"), "positions.3.float32: holds 12 bytes");
  }
  {
    auto m = valid_members();
    replace(m, "positions.3.float32", "positions.3.int32", le_bytes(kPositions));
    write_zip(dir.file("posname.trx"), m);
    expect_input_error(dir.file("posname.trx"), "positions.3.int32");
  }
  {
    auto m = valid_members();
    replace(m, "offsets.uint32", "offsets.float32", le_bytes(std::vector<float>{0, 2, 3, 6}));
    write_zip(dir.file("offname.trx"), m);
    expect_input_error(dir.file("offname.trx"), "offsets.float32");
  }
  {
    auto m = valid_members();
    m.erase(m.begin() + 1);
    write_zip(dir.file("nopos.trx"), m);
    expect_input_error(dir.file("nopos.trx"), "missing member positions");
  }
  {
    auto m = valid_members();
    replace(m, "groups/a.uint8", "groups/a.uint8", le_bytes(std::vector<std::uint8_t>{3}));
    write_zip(dir.file("group.trx"), m);
    expect_input_error(dir.file("group.trx"), "groups/a.uint8: entry 0 is not a streamline index below 3");
  }
  {
    auto m = valid_members();
    replace(m, "groups/b.int16", "groups/b.int16", le_bytes(std::vector<std::int16_t>{-1}));
    write_zip(dir.file("neg.trx"), m);
    expect_input_error(dir.file("neg.trx"), "groups/b.int16");
  }
  {
    auto m = valid_members();
    replace(m, "header.json", "header.json", text("{\"NB_STREAMLINES\": 3"));
    write_zip(dir.file("json.trx"), m);
    expect_input_error(dir.file("json.trx"), "header.json: not a JSON object");
    replace(m, "header.json", "header.json", text("{\"NB_STREAMLINES\": -3, \"NB_VERTICES\": 6}"));
    write_zip(dir.file("json2.trx"), m);
    expect_input_error(dir.file("json2.trx"), "NB_STREAMLINES is not a non-negative integer");
  }
  {
    auto m = valid_members();
    replace(m, "positions.3.float32", "positions.3.float32",
            le_bytes(std::vector<float>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16,
                                        std::numeric_limits<float>::quiet_NaN()}));
    write_zip(dir.file("nan.trx"), m);
    expect_input_error(dir.file("nan.trx"), "vertex 5 has a non-finite coordinate");
  }
}

TEST(ReadTrxBroken, NotAZipCorruptMemberAndMissingFile) {
  vxl::test::ScratchDir dir;
  std::ofstream(dir.file("junk.trx"), std::ios::binary) << "this is not a zip archive at all";
  expect_input_error(dir.file("junk.trx"), "zip");

  // Flip one byte of a stored member's data: the CRC check must catch it.
  write_zip(dir.file("crc.trx"), valid_members());
  {
    std::fstream f(dir.file("crc.trx"), std::ios::binary | std::ios::in | std::ios::out);
    f.seekp(30 + 11 + 2);  // inside header.json's data (local header 30 bytes + name 11 bytes)
    f.put('#');
  }
  expect_input_error(dir.file("crc.trx"), "header.json");

  // Truncated archive: the end-of-central-directory record is gone.
  write_zip(dir.file("cut.trx"), valid_members());
  std::filesystem::resize_file(dir.file("cut.trx"), 100);
  expect_input_error(dir.file("cut.trx"), "zip");

  EXPECT_THROW((void)vxl::read_trx(dir.file("absent.trx")), vxl::Error);
}

}  // namespace
