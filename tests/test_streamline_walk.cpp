// The walk through a .vxl's streamlines decodes on several threads in batches, and hands every streamline and
// voxline on in table order as one thread does; a damaged file stops it with the error one thread would meet
// first.
#include <cstring>
#include <string>
#include <vector>

#include "converter/convert/convert.h"
#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_streamlines.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;

// Everything a walk hands on, in the order it does.
struct WalkRecord {
  std::vector<std::uint64_t> streamlines;
  std::vector<float> points;
  std::vector<std::uint64_t> visits;  // per voxline: streamline, voxel, first vertex, own points, flags
  std::string error;
};

WalkRecord record_walk(const VxlFile& f, unsigned threads, bool with_voxlines) {
  WalkRecord r;
  WalkCallbacks cb;
  cb.threads = threads;
  cb.read_points = [](std::uint64_t s) { return s % 3 != 1; };
  cb.streamline = [&](std::uint64_t s, std::span<const float> xyz) {
    r.streamlines.push_back(s);
    r.points.insert(r.points.end(), xyz.begin(), xyz.end());
  };
  if (with_voxlines)
    cb.voxline = [&](const VoxlineVisit& v) {
      r.visits.insert(r.visits.end(), {v.streamline, v.voxel, v.first_vertex, v.own_points,
                                       std::uint64_t(v.synthetic_first) | std::uint64_t(v.first_of_streamline) << 1 |
                                           std::uint64_t(v.connected) << 2});
    };
  try {
    walk_streamlines(f, cb);
  } catch (const Error& e) {
    r.error = e.what();
  }
  return r;
}

// A file of about 1.1M points: three of the walk's batches.
std::string converted_synth(const ScratchDir& dir) {
  SynthSettings synth;
  synth.streamlines = 20000;
  const std::string path = dir.file("s.vxl");
  convert_tractogram(synthesize_tractogram(synth), path, {});
  return path;
}

TEST(StreamlineWalk, OnSeveralThreadsItHandsOnWhatOneThreadDoes) {
  ScratchDir dir;
  const VxlFile f = VxlFile::open(converted_synth(dir));
  ASSERT_GT(f.meta().point_count, 1000000u);
  for (bool with_voxlines : {false, true}) {
    const WalkRecord one = record_walk(f, 1, with_voxlines);
    ASSERT_EQ(one.error, "");
    ASSERT_EQ(one.streamlines.size(), 13333u);  // s % 3 != 1 of 20,000
    EXPECT_EQ(one.visits.size(), with_voxlines ? 5 * f.meta().voxline_count : 0u);
    for (unsigned threads : {2u, 3u}) {
      const WalkRecord many = record_walk(f, threads, with_voxlines);
      EXPECT_EQ(many.error, "");
      EXPECT_EQ(many.streamlines, one.streamlines) << threads << " threads";
      EXPECT_TRUE(many.points == one.points) << threads << " threads";
      EXPECT_EQ(many.visits, one.visits) << threads << " threads";
    }
  }
}

// Two faults, a connecting vertex changed early in the file and a voxline naming no voxel after it (in the same
// batch, or batches on): every thread count reports the early one, and the other alone where the early one is
// not there.
TEST(StreamlineWalk, ADamagedFileStopsItAtTheFaultOneThreadMeetsFirst) {
  ScratchDir dir;
  const std::string good = converted_synth(dir);
  const std::vector<char> bytes = test::slurp(good);
  std::uint64_t vert_at = 0, vxln_at = 0, connector = 0, early_streamline = 0;
  std::vector<std::uint64_t> later_voxlines;
  {
    const VxlFile f = VxlFile::open(good);
    ASSERT_EQ(f.position_encoding(), PositionEncoding::Packed);
    vert_at = f.find_section(section_id("VERT"))->offset;
    vxln_at = f.find_section(section_id("VXLN"))->offset;
    // The first connecting vertex from streamline 10 on, of a streamline the walks read.
    WalkCallbacks cb;
    cb.voxline = [&](const VoxlineVisit& v) {
      if (connector == 0 && v.streamline >= 10 && v.streamline % 3 == 0 && v.connected) {
        connector = v.first_vertex + v.own_points;
        early_streamline = v.streamline;
      }
    };
    walk_streamlines(f, cb);
    later_voxlines = {f.streamline_first_voxline()[100], f.streamline_first_voxline()[19000]};
  }
  ASSERT_GT(connector, 0u);
  ASSERT_LT(early_streamline, 100u);
  for (const std::uint64_t later : later_voxlines) {
    std::vector<char> late = bytes;
    const std::uint32_t no_voxel = 0xFFFFFFFFu;
    std::memcpy(late.data() + vxln_at + 8 * later, &no_voxel, 4);  // VoxlineEntry.voxel
    std::vector<char> both = late;
    std::uint32_t word = 0;
    std::memcpy(&word, both.data() + vert_at + 4 * connector, 4);
    word ^= 0x200u;  // x's quantum moved by half the voxel
    std::memcpy(both.data() + vert_at + 4 * connector, &word, 4);
    test::write_file(dir.file("late.vxl"), late);
    test::write_file(dir.file("both.vxl"), both);
    const VxlFile late_file = VxlFile::open(dir.file("late.vxl"));
    const VxlFile both_file = VxlFile::open(dir.file("both.vxl"));
    for (unsigned threads : {1u, 2u, 3u}) {
      const WalkRecord l = record_walk(late_file, threads, false);
      EXPECT_NE(l.error.find("voxline refers to a voxel past the table"), std::string::npos) << l.error;
      EXPECT_NE(l.error.find(std::to_string(vxln_at + 8 * later)), std::string::npos) << l.error;
      const WalkRecord b = record_walk(both_file, threads, false);
      EXPECT_NE(b.error.find("connecting vertex differs"), std::string::npos) << threads << " threads: " << b.error;
      EXPECT_TRUE(b.streamlines.empty() || b.streamlines.back() < early_streamline) << threads << " threads";
    }
  }
}

}  // namespace
}  // namespace vxl
