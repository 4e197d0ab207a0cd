// The .vxl container: write -> open -> verify, and detection of every single-byte change and every
// truncation (spec §7), for both position encodings (spec §5.4).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>

#include "converter/convert/convert.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_positions.h"
#include "format/vxl_streamlines.h"
#include "format/vxl_verify.h"
#include "tests/reseal_checksums.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;
using test::slurp;

// A small tractogram with voxel changes, a long step (synthetic points), one-point and empty
// streamlines, and a group.
Tractogram small_tractogram() {
  Tractogram t;
  t.source.path = "small.tck";
  t.source.format = "tck";
  for (int s = 0; s < 12; ++s) {
    std::vector<float> pts;
    for (int i = 0; i < 9; ++i) pts.insert(pts.end(), {3.0f * i + s, 2.0f * s - i, 0.5f * i * s});
    t.add_streamline(pts.data(), 9);
  }
  float one[3] = {1, 1, 1};
  t.add_streamline(one, 1);
  t.add_streamline(one, 0);
  float jump[6] = {0, 0, 0, 40, 1, 1};
  t.add_streamline(jump, 2);
  t.groups.push_back({"bundle", {0, 3, 14}});
  return t;
}

void dump(const std::string& p, const std::vector<char>& bytes, std::size_t n) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(n));
}

class VxlFormat : public ::testing::TestWithParam<PositionEncoding> {
 protected:
  void SetUp() override {
    ConvertSettings s;
    s.voxel_size = 8;
    s.positions = GetParam();
    convert_tractogram(small_tractogram(), path(), s);
  }
  std::string path() const { return dir.file("small.vxl"); }
  ScratchDir dir;
};

// Found by fuzz_vxl (UBSan: memcpy with a null destination): a group without members, which a TRX may
// hold, is kept and read back without undefined behaviour.
TEST(VxlGroups, AGroupWithoutMembersIsKept) {
  ScratchDir dir;
  Tractogram t = small_tractogram();
  t.groups.push_back({"empty", {}});
  ConvertSettings s;
  s.voxel_size = 8;
  convert_tractogram(std::move(t), dir.file("g.vxl"), s);
  const std::vector<StreamlineGroup> groups = VxlFile::open(dir.file("g.vxl")).groups();
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0].members, (std::vector<std::uint64_t>{0, 3, 14}));
  EXPECT_EQ(groups[1].name, "empty");
  EXPECT_TRUE(groups[1].members.empty());
  EXPECT_TRUE(verify_vxl(dir.file("g.vxl")).valid);
}

TEST_P(VxlFormat, RoundTripThroughTheWalk) {
  VerifyResult r = verify_vxl(path());
  ASSERT_TRUE(r.valid) << r.problem;
  VxlFile f = VxlFile::open(path());
  const bool packed = GetParam() == PositionEncoding::Packed;
  // The lowest version that holds the file (spec §10): streamline lengths and levels of detail (the default), 2.4.
  EXPECT_EQ(f.header().version_major, 2);
  EXPECT_EQ(f.header().version_minor, 4);
  EXPECT_GT(f.level_count(), 1u);
  EXPECT_EQ(f.position_encoding(), GetParam());
  EXPECT_EQ(f.find_section(section_id("VERT"))->size, f.meta().vertex_count * (packed ? 4 : 12));
  EXPECT_EQ(f.header().file_size % 64, 0u);
  for (const SectionEntry& e : f.sections()) EXPECT_EQ(e.offset % 64, 0u);
  Tractogram expected = small_tractogram();
  std::vector<float> got;
  std::vector<std::uint64_t> offsets = {0};
  walk_streamlines(f, {[&](std::uint64_t, std::span<const float> xyz) {
                         got.insert(got.end(), xyz.begin(), xyz.end());
                         offsets.push_back(got.size() / 3);
                       },
                       {},
                       {}});
  EXPECT_EQ(offsets, expected.offsets);
  if (!packed) {
    EXPECT_EQ(got, expected.positions);
  } else {
    double bound = 0, worst = 0;
    for (const VoxelEntry& v : f.voxels()) bound = std::max(bound, packed_error_bound(v));
    ASSERT_EQ(got.size(), expected.positions.size());
    for (std::size_t k = 0; k < got.size(); ++k)
      worst = std::max(worst, std::abs(double(got[k]) - double(expected.positions[k])));
    EXPECT_LE(worst, bound);
    EXPECT_GT(worst, 0.0) << "8 mm voxels at 10 bits cannot hold these coordinates exactly";
  }
  EXPECT_GT(f.meta().synthetic_point_count, 0u);
  auto groups = f.groups();
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].members, (std::vector<std::uint64_t>{0, 3, 14}));
}

TEST_P(VxlFormat, EverySingleByteChangeIsDetected) {
  std::vector<char> good = slurp(path());
  ASSERT_GT(good.size(), 1000u);
  std::string bad = dir.file("bad.vxl");
  std::size_t undetected = 0;
  for (std::size_t pos = 0; pos < good.size(); ++pos) {
    std::vector<char> b = good;
    b[pos] = static_cast<char>(b[pos] ^ (1 + pos % 255));
    dump(bad, b, b.size());
    VerifyResult r = verify_vxl(bad);
    if (r.valid) {
      ++undetected;
      ADD_FAILURE() << "change at byte " << pos << " not detected";
    }
    // Opening without verify must never read out of bounds (ASan watches this), whatever it decides.
    try {
      VxlFile f = VxlFile::open(bad);
      walk_streamlines(f, {});
    } catch (const Error&) {
    }
    if (undetected > 5) break;
  }
}

TEST_P(VxlFormat, EveryTruncationIsRefused) {
  std::vector<char> good = slurp(path());
  std::string bad = dir.file("bad.vxl");
  for (std::size_t n = 0; n < good.size(); n += (n < 256 ? 1 : 7)) {
    dump(bad, good, n);
    EXPECT_THROW(VxlFile::open(bad), Error) << n;
    EXPECT_FALSE(verify_vxl(bad).valid) << n;
  }
}

TEST_P(VxlFormat, NewerMajorVersionIsUnsupported) {
  std::vector<char> b = slurp(path());
  b[8] = 3;
  dump(dir.file("v3.vxl"), b, b.size());
  try {
    VxlFile::open(dir.file("v3.vxl"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
  }
}

TEST_P(VxlFormat, EmptyTractogramMakesAValidFile) {
  Tractogram t;
  t.source.path = "empty.tck";
  ConvertSettings s;
  s.positions = GetParam();
  convert_tractogram(std::move(t), dir.file("empty.vxl"), s);
  VerifyResult r = verify_vxl(dir.file("empty.vxl"));
  EXPECT_TRUE(r.valid) << r.problem;
  EXPECT_EQ(VxlFile::open(dir.file("empty.vxl")).meta().voxel_count, 0u);
}

TEST_P(VxlFormat, FailedConversionLeavesNoOutput) {
  Tractogram t = small_tractogram();
  t.positions[5] = NAN;
  EXPECT_THROW(convert_tractogram(std::move(t), dir.file("nan.vxl"), {}), Error);
  EXPECT_FALSE(std::filesystem::exists(dir.file("nan.vxl")));
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename(), "small.vxl") << "left behind: " << entry.path();
}

// Geometry that open() allows within a voxel's margin but verify pins (spec §5.1, §5.3, §6.1): a tight bound
// that is not its vertices' extreme, META bounds that are not the tight bounds' extremes, a grid one voxel too
// large. Each is made behind valid checksums, so only the geometry check can catch it.
TEST_P(VxlFormat, VerifyRefusesBoundsAndAGridThatAreNotTheVerticesExtremes) {
  ASSERT_TRUE(verify_vxl(path()).valid);
  const VxlFile f = VxlFile::open(path());
  const std::uint64_t voxt = f.find_section(section_id("VOXT"))->offset;
  const std::uint64_t meta = f.find_section(section_id("META"))->offset;
  struct Damage {
    std::uint64_t at;
    std::function<void(char*)> apply;
    std::string expected;
    bool tight_bound;  // packed, it moves the decoded vertices
  };
  // Adds d to the field of d's type at p.
  auto add = [](auto d) {
    return [d](char* p) {
      decltype(d) v;
      std::memcpy(&v, p, sizeof v);
      v += d;
      std::memcpy(p, &v, sizeof v);
    };
  };
  const std::vector<Damage> damages = {
      {voxt + 16, add(-1.0f), "tight bounds of voxel 0 are not the extremes of its vertices", true},
      {voxt + 28 + 8, add(0.5f), "tight bounds of voxel 0 are not the extremes of its vertices", true},
      {meta + 104, add(-0.5), "META bounds are not the extremes of the voxels' tight bounds", false},
      {meta + 88, add(std::int32_t{1}), "their coordinates on x run from 0 to", false},
  };
  for (const Damage& d : damages) {
    SCOPED_TRACE(d.expected);
    std::vector<char> b = slurp(path());
    d.apply(b.data() + d.at);
    ASSERT_TRUE(test::reseal_checksums(b.data(), b.size()));
    dump(dir.file("bad.vxl"), b, b.size());
    const VerifyResult r = verify_vxl(dir.file("bad.vxl"));
    EXPECT_FALSE(r.valid);
    // With packed positions a moved tight bound moves the decoded vertices instead: the connecting vertices or the
    // lengths no longer agree, and that is what verify reports.
    if (GetParam() == PositionEncoding::Packed && d.tight_bound) continue;
    EXPECT_NE(r.problem.find(d.expected), std::string::npos) << r.problem;
  }
  if (GetParam() != PositionEncoding::Packed) return;
  // Packed, the words themselves must reach the bounds: voxel 0's vertices at quantum 0 on x moved to quantum 1.
  std::vector<char> b = slurp(path());
  const std::uint64_t vert = f.find_section(section_id("VERT"))->offset;
  for (std::uint64_t k = 0; k < f.voxels()[0].vertex_count; ++k) {
    std::uint32_t w;
    std::memcpy(&w, b.data() + vert + 4 * k, 4);
    if ((w & kPackedAxisMask) == 0) w |= 1;
    std::memcpy(b.data() + vert + 4 * k, &w, 4);
  }
  ASSERT_TRUE(test::reseal_checksums(b.data(), b.size()));
  dump(dir.file("bad.vxl"), b, b.size());
  const VerifyResult r = verify_vxl(dir.file("bad.vxl"));
  EXPECT_FALSE(r.valid);
  EXPECT_NE(r.problem.find("tight bounds of voxel 0 are not the extremes of its vertices"), std::string::npos)
      << r.problem;
}

INSTANTIATE_TEST_SUITE_P(Positions, VxlFormat, ::testing::Values(PositionEncoding::Float32, PositionEncoding::Packed),
                         [](const ::testing::TestParamInfo<PositionEncoding>& info) {
                           return std::string(position_encoding_name(info.param));
                         });

}  // namespace
}  // namespace vxl
