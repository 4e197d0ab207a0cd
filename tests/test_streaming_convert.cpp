// convert --memory-limit (streaming_convert.h): the output must be byte-identical to the in-memory
// conversion, the work must really be split, and a limit that is too small must fail cleanly.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <set>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

#include "converter/convert/convert.h"
#include "converter/convert/streaming_convert.h"
#include "converter/export/tck_writer.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/tck_stream.h"
#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/base/memory_size.h"
#include "format/vxl_file.h"
#include "format/vxl_verify.h"
#include "tests/address_sanitizer.h"
#include "tests/mrtrix_test_files.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::raw;
using test::ScratchDir;

using vxl::test::kMiB;

void write_synth_tck(const std::string& path, std::uint64_t streamlines, std::uint64_t seed = 1) {
  Tractogram t = synthesize_tractogram({streamlines, seed});
  TckWriter w(path, t.streamline_count());
  for (std::uint64_t i = 0; i < t.streamline_count(); ++i)
    w.add({t.positions.data() + 3 * t.offsets[i], 3 * (t.offsets[i + 1] - t.offsets[i])});
  w.finish();
}

// A TCK with the given datatype and raw data bytes (as in test_read_tck.cpp).
void write_raw_tck(const std::string& path, const std::string& datatype, const std::string& data,
                   const std::string& extra = "") {
  test::write_mrtrix_file(path, "mrtrix tracks", datatype, data, extra);
}

ConvertSettings settings_for(double voxel_size, const std::string& orders = "axis") {
  ConvertSettings s;
  s.voxel_size = voxel_size;
  s.orders = orders;
  s.threads = 2;  // fixed, so that the sort buffers (per thread) and hence the ranges do not depend on the machine
  return s;
}

// Converts `tck` in memory and with `limit`; expects the same bytes and returns the streaming summary.
ConvertSummary expect_identical(const ScratchDir& dir, const std::string& tck, ConvertSettings settings,
                                std::uint64_t limit) {
  const std::string whole = dir.file("whole.vxl"), limited = dir.file("limited.vxl");
  convert_tractogram(read_tractogram(tck), whole, settings);
  settings.memory_limit = limit;
  ConvertSummary s = convert_streaming(tck, limited, settings);
  std::vector<char> a = test::slurp(whole), b = test::slurp(limited);
  EXPECT_GT(a.size(), 0u);
  EXPECT_TRUE(a == b) << "the limited conversion differs from the in-memory one (" << a.size() << " vs " << b.size()
                      << " bytes)";
  VerifyResult v = verify_vxl(limited);
  EXPECT_TRUE(v.valid) << v.problem;
  EXPECT_EQ(s.passes, s.partitions + (s.points > 0 ? 2 : 1));  // scan, plan (when there are points), one per range
  EXPECT_EQ(s.partition_starts.size(), s.partitions);
  return s;
}

// Streamlines whose voxlines fall in voxels of more than one range.
std::uint64_t streamlines_across_ranges(const std::string& vxl, const std::vector<std::uint64_t>& starts) {
  VxlFile f = VxlFile::open(vxl);
  auto range_of = [&](std::uint32_t voxel) {
    return std::upper_bound(starts.begin(), starts.end(), voxel) - starts.begin();
  };
  std::uint64_t across = 0;
  auto strm = f.streamline_first_voxline();
  for (std::size_t k = 0; k + 1 < strm.size(); ++k) {
    std::set<std::ptrdiff_t> ranges;
    for (std::uint64_t j = strm[k]; j < strm[k + 1]; ++j) ranges.insert(range_of(f.voxlines()[j].voxel));
    across += ranges.size() > 1;
  }
  return across;
}

TEST(StreamingConvert, TckStreamReadsWhatReadTckReads) {
  ScratchDir dir;
  const float nan = NAN, inf = INFINITY;
  struct Case {
    const char* name;
    std::string datatype, data, extra;
  } cases[] = {
      {"synth.tck", "", "", ""},
      // no Inf terminator, 5 trailing bytes, last streamline without a NaN, an empty streamline, stale count
      {"open_end.tck", "Float32LE",
       raw<float>({1, 2, 3, 4, 5, 6, nan, nan, nan, nan, nan, nan, 7, 8, 9, 10, 11, 12}) + "abcde", "count: 7\n"},
      {"f64be.tck", "Float64BE", raw<double>({1, 2, 3, 1e300, 1, 1, nan, 0, 0, 5, 5, 5, nan, 0, 0, inf, 0, 0}, true),
       ""},
      {"empty.tck", "Float32LE", raw<float>({inf, inf, inf}), "count: 0\n"},
      {"delimiters.tck", "Float32LE", raw<float>({nan, 0, 0, nan, 0, 0, nan, 0, 0, inf, 0, 0}), ""},
  };
  for (const Case& c : cases) {
    const std::string path = dir.file(c.name);
    if (c.datatype.empty())
      write_synth_tck(path, 300);
    else
      write_raw_tck(path, c.datatype, c.data, c.extra);
    Tractogram whole = read_tck(path);
    // Odd chunk and batch sizes, so that triplets, streamlines and batches end everywhere.
    for (std::uint64_t chunk : {12ull * 7, 24ull * 5 + 12, 4096ull}) {
      for (std::uint64_t batch_points : {1ull, 97ull, 1ull << 30}) {
        SCOPED_TRACE(std::string(c.name) + " chunk " + std::to_string(chunk) + " batch " +
                     std::to_string(batch_points));
        TckStream stream(path, 1 << 20, chunk);
        for (int pass = 0; pass < 2; ++pass) {
          if (pass > 0) stream.rewind();
          Tractogram all, batch;
          std::uint64_t batches = 0;
          while (stream.next(batch, batch_points)) {
            ASSERT_GT(batch.streamline_count(), 0u);
            ++batches;
            for (std::uint64_t k = 0; k < batch.streamline_count(); ++k)
              all.add_streamline(batch.positions.data() + 3 * batch.offsets[k],
                                 batch.offsets[k + 1] - batch.offsets[k]);
          }
          EXPECT_FALSE(stream.next(batch, batch_points));  // stays at the end
          EXPECT_EQ(all.offsets, whole.offsets);
          EXPECT_TRUE(all.positions == whole.positions);  // bit-exact (no NaNs in positions)
          if (batch_points == 1) {
            EXPECT_EQ(batches, whole.streamline_count());
          }
          ASSERT_TRUE(stream.complete());
          EXPECT_EQ(stream.source().xxh3_128, whole.source.xxh3_128);
          EXPECT_EQ(stream.source().warnings, whole.source.warnings);
          EXPECT_EQ(stream.source().header, whole.source.header);
          EXPECT_EQ(stream.source().bytes, whole.source.bytes);
          EXPECT_EQ(stream.source().dtype, whole.source.dtype);
        }
      }
    }
  }
}

TEST(StreamingConvert, TckStreamReportsTheSameErrorsAsReadTck) {
  ScratchDir dir;
  const std::string bad_y = dir.file("bad_y.tck"), no_end = dir.file("no_end.tck");
  write_raw_tck(bad_y, "Float32LE", raw<float>({1, 2, 3, 4, NAN, 6, NAN, 0, 0}));
  std::ofstream(no_end, std::ios::binary) << "mrtrix tracks\ndatatype: Float32LE\nfile: . 40\n";
  for (const std::string& path : {bad_y, no_end}) {
    std::string expected;
    try {
      read_tck(path);
    } catch (const Error& e) {
      expected = e.what();
    }
    ASSERT_FALSE(expected.empty());
    try {
      TckStream stream(path, 1 << 20, 12);
      Tractogram batch;
      while (stream.next(batch, 1)) {
      }
      ADD_FAILURE() << "no error for " << path;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), expected);
      EXPECT_EQ(e.kind(), ErrorKind::Input);
    }
  }
}

// The synth set at 10 mm: a few hundred voxels, every streamline crosses several, so cutting the table
// into ranges cuts streamlines.
TEST(StreamingConvert, SynthAt10mmIsIdenticalAcrossSeveralRanges) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck");
  // 12000 streamlines: a range holds 4 bytes a packed vertex, so it takes this many to need several.
  write_synth_tck(tck, 12000);
  ConvertSummary s = expect_identical(dir, tck, settings_for(10.0), 21 * kMiB);
  EXPECT_GE(s.partitions, 3u);
  // Float32 positions are held and written as they are, 12 bytes a vertex.
  ConvertSettings float32 = settings_for(10.0);
  float32.positions = PositionEncoding::Float32;
  s = expect_identical(dir, tck, float32, 24 * kMiB);
  EXPECT_GE(s.partitions, 3u);
  EXPECT_GT(streamlines_across_ranges(dir.file("limited.vxl"), s.partition_starts), 1000u);
}

// 1 mm voxels: tens of thousands of voxels, and steps of up to 1.25 mm that cross two faces, so points
// are added at voxel faces (spec §6.3).
TEST(StreamingConvert, ManySmallVoxelsAndSplitLongStepsAreIdentical) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck");
  write_synth_tck(tck, 4000, 7);
  // One level: the voxel table of 1 mm voxels (44 MiB with what is taken before it) then leaves room in
  // 51 MiB for a few ranges (and the voxlines of two batches being placed: about one per point here).
  ConvertSettings one_level = settings_for(1.0);
  one_level.levels = 1;
  ConvertSummary s = expect_identical(dir, tck, one_level, 51 * kMiB);
  EXPECT_GT(s.voxels, 20000u);
  EXPECT_GT(s.synthetic_points, 100u);
  EXPECT_GE(s.partitions, 2u);
  EXPECT_GT(streamlines_across_ranges(dir.file("limited.vxl"), s.partition_starts), 100u);
  // Levels of detail place each depth's voxlines separately in every block: identical too (in several
  // ranges at 10 mm: SynthAt10mmIsIdenticalAcrossSeveralRanges; at 1 mm their voxel table leaves no limit
  // between refusing the table and one range).
  expect_identical(dir, tck, settings_for(1.0), 90 * kMiB);
}

// Steps of about 11 mm across 10 mm voxels (many jump a voxel) along all axes, with the 14-order set.
TEST(StreamingConvert, LongStepsAndDiagonalOrdersAreIdentical) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck");
  {
    TckWriter w(tck, 20000);
    for (int s = 0; s < 20000; ++s) {
      std::vector<float> pts;
      for (int i = 0; i < 12; ++i) {
        const float a = 0.37f * float(s) + 0.9f * float(i);
        pts.insert(pts.end(),
                   {12.0f * std::cos(a) + 0.01f * float(s), 12.0f * std::sin(a), 3.1f * float(i) - 0.02f * float(s)});
      }
      w.add(pts);
    }
    w.finish();
  }
  ConvertSummary s = expect_identical(dir, tck, settings_for(10.0, "axis+diag"), 24 * kMiB);
  EXPECT_GT(s.synthetic_points, 1000u);
  EXPECT_GE(s.partitions, 2u);
  // Per-voxel random directions (the VDIR section) come out the same when streamed.
  ConvertSummary r = expect_identical(dir, tck, settings_for(10.0, "random:8"), 24 * kMiB);
  EXPECT_GE(r.partitions, 2u);
}

// The placing passes cut the streamlines by the voxel runs the counting pass kept where the limit leaves
// room for them, and voxelise again where it does not: the same bytes either way, in one range or several,
// with points added at voxel faces (whose streamlines are voxelised again) or without. Likewise the voxel
// index's lists, filled as the first range is placed where the limit holds them, else sorted from the tables
// read back at the write stage.
TEST(StreamingConvert, VoxelRunsAndIndexListsAreKeptWhereTheyFitAndTheBytesAreTheSame) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck");
  write_synth_tck(tck, 12000);
  ConvertSummary s = expect_identical(dir, tck, settings_for(10.0), 256 * kMiB);
  EXPECT_TRUE(s.voxelised_once);
  EXPECT_TRUE(s.voxel_index_while_placing);
  EXPECT_EQ(s.partitions, 1u);
  s = expect_identical(dir, tck, settings_for(10.0), 21 * kMiB);  // several ranges, no room for the runs
  EXPECT_FALSE(s.voxelised_once);
  EXPECT_FALSE(s.voxel_index_while_placing) << "no room for the index's lists either";
  EXPECT_GE(s.partitions, 3u);
  // Several ranges beside the runs: streamlines with no voxel in a range are skipped past their runs (under
  // 256 MiB, so that a range holds its vertices and the request cuts it).
  ConvertSettings settings = settings_for(10.0);
  settings.memory_limit = 200 * kMiB;
  StreamingTuning small_ranges;
  small_ranges.range_bytes = 1 * kMiB;
  const std::string whole = dir.file("whole.vxl"), ranged = dir.file("ranged.vxl");
  s = convert_streaming(tck, ranged, settings, small_ranges);
  EXPECT_TRUE(s.voxelised_once);
  EXPECT_TRUE(s.voxel_index_while_placing) << "the voxel index's lists filled by the first of several ranges";
  EXPECT_GE(s.partitions, 3u);
  EXPECT_TRUE(test::slurp(whole) == test::slurp(ranged));
  EXPECT_GT(streamlines_across_ranges(ranged, s.partition_starts), 1000u);
  // 1 mm voxels: points added at voxel faces, their streamlines voxelised again in the placing pass.
  write_synth_tck(tck, 2000, 7);
  ConvertSettings fine = settings_for(1.0);
  fine.levels = 1;
  s = expect_identical(dir, tck, fine, 256 * kMiB);
  EXPECT_TRUE(s.voxelised_once);
  EXPECT_GT(s.synthetic_points, 100u);
  settings = fine;
  settings.memory_limit = 200 * kMiB;
  s = convert_streaming(tck, ranged, settings, small_ranges);
  EXPECT_TRUE(s.voxelised_once);
  EXPECT_GE(s.partitions, 2u);
  EXPECT_TRUE(test::slurp(whole) == test::slurp(ranged));
}

// The voxel index's lists filled while placing with one thread (the read after each batch's items, the placing
// before the staging) and with float32 positions (the placing in one item): the in-memory conversion's bytes.
TEST(StreamingConvert, TheVoxelIndexListsFillWithOneThreadAndWithFloat32Positions) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck");
  write_synth_tck(tck, 12000);
  ConvertSettings one = settings_for(10.0);
  one.threads = 1;
  EXPECT_TRUE(expect_identical(dir, tck, one, 256 * kMiB).voxel_index_while_placing);
  ConvertSettings float32 = settings_for(10.0);
  float32.positions = PositionEncoding::Float32;
  EXPECT_TRUE(expect_identical(dir, tck, float32, 256 * kMiB).voxel_index_while_placing);
}

// Float64 big-endian source, an empty streamline, no Inf terminator: the provenance (checksum, header,
// warnings) must come out the same too.
TEST(StreamingConvert, HandMadeSourceWithWarningsIsIdentical) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck");
  std::vector<double> values;
  for (int s = 0; s < 200; ++s) {
    for (int i = 0; i < 30; ++i) values.insert(values.end(), {0.5 * i + s, 2.0 * std::sin(0.1 * i * s), 0.25 * i});
    values.insert(values.end(), {NAN, 0, 0});
    if (s == 50) values.insert(values.end(), {NAN, 0, 0});
  }
  std::string data;
  for (double v : values) data += raw<double>({v}, true);
  data += raw<double>({1, 1, 1}, true);  // an open last streamline, no terminator
  write_raw_tck(tck, "Float64BE", data, "count: 5\n");
  ConvertSummary s = expect_identical(dir, tck, settings_for(4.0), 19 * kMiB);
  EXPECT_EQ(s.streamlines, 202u);
  EXPECT_EQ(s.warnings, read_tck(tck).source.warnings);
  EXPECT_EQ(s.warnings.size(), 4u);
}

TEST(StreamingConvert, EmptySourcesAreIdentical) {
  ScratchDir dir;
  const std::string none = dir.file("none.tck"), empties = dir.file("empties.tck");
  write_raw_tck(none, "Float32LE", raw<float>({INFINITY, 0, 0}), "count: 0\n");
  write_raw_tck(empties, "Float32LE", raw<float>({NAN, 0, 0, NAN, 0, 0, INFINITY, 0, 0}));
  EXPECT_EQ(expect_identical(dir, none, settings_for(10.0), 32 * kMiB).streamlines, 0u);
  EXPECT_EQ(expect_identical(dir, empties, settings_for(10.0), 32 * kMiB).streamlines, 2u);
}

// Every real TCK fixture (multi-line headers, big-endian, Float64, stale counts, no terminator, ...):
// the same bytes, or the same error, as the in-memory conversion.
TEST(StreamingConvert, RealTckFixturesAreIdentical) {
  VXL_REQUIRE_REAL_DATA();
  ScratchDir dir;
  int compared = 0;
  for (const auto& entry : std::filesystem::directory_iterator(test::real_data_dir())) {
    if (entry.path().extension() != ".tck") continue;
    const std::string tck = entry.path().string(), whole = dir.file("whole.vxl"), limited = dir.file("limited.vxl");
    SCOPED_TRACE(tck);
    std::filesystem::remove(whole);
    std::filesystem::remove(limited);
    ConvertSettings settings = settings_for(5.0);
    std::optional<ErrorKind> expected;
    try {
      convert_tractogram(read_tractogram(tck), whole, settings);
    } catch (const Error& e) {
      expected = e.kind();
    }
    settings.memory_limit = 64 * kMiB;
    try {
      convert_streaming(tck, limited, settings);
      EXPECT_FALSE(expected) << "the in-memory conversion failed, the limited one did not";
      EXPECT_TRUE(test::slurp(whole) == test::slurp(limited));
      ++compared;
    } catch (const Error& e) {
      EXPECT_EQ(expected, e.kind()) << e.what();
      EXPECT_FALSE(std::filesystem::exists(limited));
    }
  }
  EXPECT_GE(compared, 10);
}

// A limit below what some part of the work needs fails before anything is written, says which part,
// and suggests a limit; following the suggestions leads to a conversion (each one may uncover the
// next part that does not fit).
TEST(StreamingConvert, TooSmallALimitFailsCleanlyWithAUsefulSuggestion) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), out = dir.file("out.vxl");
  write_synth_tck(tck, 4000);
  ConvertSettings settings = settings_for(1.0);
  settings.memory_limit = 4 * kMiB;
  int failures = 0;
  for (; failures < 6; ++failures) {
    try {
      convert_streaming(tck, out, settings);
      break;
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(e.kind(), ErrorKind::Unsupported) << what;
      EXPECT_NE(what.find("--memory-limit " + format_memory_size(settings.memory_limit) + " is too small"),
                std::string::npos)
          << what;
      EXPECT_NE(what.find(" needs "), std::string::npos) << what;
      // nothing at the output path, and no temporary file beside it
      for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
        EXPECT_EQ(entry.path().filename(), "in.tck") << what;
      const std::size_t at = what.find("use --memory-limit ");
      ASSERT_NE(at, std::string::npos) << what;
      std::string suggestion = what.substr(at + 19);
      suggestion = suggestion.substr(0, suggestion.find(' '));
      std::optional<std::uint64_t> next = parse_memory_size(suggestion);
      ASSERT_TRUE(next) << what;
      EXPECT_GT(*next, settings.memory_limit) << what;
      settings.memory_limit = *next;
    }
  }
  EXPECT_GE(failures, 1);
  EXPECT_LT(failures, 6) << "the suggestions did not lead to a limit that works";
  EXPECT_TRUE(verify_vxl(out).valid);
}

// One streamline longer than the limit can hold: refused while it is being read, not after.
TEST(StreamingConvert, AStreamlineTooLongToHoldFailsCleanly) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), out = dir.file("out.vxl");
  {
    TckWriter w(tck, 12);
    std::vector<float> pts;
    for (int s = 0; s < 12; ++s) {
      pts.clear();
      const int n = s == 10 ? 2000000 : 50;
      for (int i = 0; i < n; ++i) pts.insert(pts.end(), {0.001f * float(i), float(s), 0.0f});
      w.add(pts);
    }
    w.finish();
  }
  ConvertSettings settings = settings_for(10.0);
  settings.memory_limit = 24 * kMiB;
  try {
    convert_streaming(tck, out, settings);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    EXPECT_NE(std::string(e.what()).find("streamline 10, of more than"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  settings.memory_limit = 128 * kMiB;  // 24 MB of points: fits
  EXPECT_EQ(convert_streaming(tck, out, settings).points, 2000550u);
}

TEST(StreamingConvert, OnlyTckSourcesStream) {
  ScratchDir dir;
  const std::string trk = dir.file("in.trk"), out = dir.file("out.vxl");
  std::ofstream(trk) << "not read";
  ConvertSettings settings = settings_for(10.0);
  settings.memory_limit = 512 * kMiB;
  try {
    convert_streaming(trk, out, settings);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    EXPECT_NE(std::string(e.what()).find("TCK sources only"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(out));
}

// The source is read several times: a change between passes must not give a silently wrong file.
TEST(StreamingConvert, ASourceThatChangesBetweenPassesIsAnInputError) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), out = dir.file("out.vxl");
  write_synth_tck(tck, 500);
  ConvertSettings settings = settings_for(10.0);
  settings.memory_limit = 64 * kMiB;
  bool changed = false;
  settings.progress = [&](const char* stage, double) {
    if (!changed && std::string(stage) == "voxelising") {
      std::ofstream(tck, std::ios::app | std::ios::binary) << "appended";
      changed = true;
    }
  };
  try {
    convert_streaming(tck, out, settings);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("changed"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(changed);
  EXPECT_FALSE(std::filesystem::exists(out));
}

// The same when the change keeps the file's size and time (points rewritten in place, the time set back): the
// placing pass finds vertices outside the bounds the counting pass found, with either position encoding.
TEST(StreamingConvert, PointsRewrittenBetweenPassesWithTheTimeKeptAreAnInputError) {
  for (const PositionEncoding positions : {PositionEncoding::Packed, PositionEncoding::Float32}) {
    SCOPED_TRACE(position_encoding_name(positions));
    ScratchDir dir;
    const std::string tck = dir.file("in.tck"), out = dir.file("out.vxl");
    write_synth_tck(tck, 500);
    ConvertSettings settings = settings_for(10.0);
    settings.positions = positions;
    settings.memory_limit = 64 * kMiB;
    bool changed = false;
    settings.progress = [&](const char* stage, double) {
      if (changed || std::string(stage).rfind("placing", 0) != 0) return;
      const auto time = std::filesystem::last_write_time(tck);
      std::fstream f(tck, std::ios::in | std::ios::out | std::ios::binary);
      std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
      const std::size_t data = std::stoul(bytes.substr(bytes.find("file: . ") + 8));
      for (std::size_t at = data; at + 12 <= bytes.size(); at += 12) {  // every point 30 mm along x
        float x;
        std::memcpy(&x, bytes.data() + at, 4);
        if (!std::isfinite(x)) continue;
        x += 30.0f;
        std::memcpy(bytes.data() + at, &x, 4);
      }
      f.seekp(0);
      f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      f.close();
      std::filesystem::last_write_time(tck, time);
      changed = true;
    };
    try {
      convert_streaming(tck, out, settings);
      ADD_FAILURE() << "converted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find("changed"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(changed);
    EXPECT_FALSE(std::filesystem::exists(out));
  }
}

TEST(StreamingConvert, MemorySizesParse) {
  EXPECT_EQ(parse_memory_size("1048576"), 1048576u);
  EXPECT_EQ(parse_memory_size("64K"), 64u << 10);
  EXPECT_EQ(parse_memory_size("512M"), 512ull << 20);
  EXPECT_EQ(parse_memory_size("512m"), 512ull << 20);
  EXPECT_EQ(parse_memory_size("2G"), 2ull << 30);
  for (const char* bad : {"", "M", "0", "0M", "-5M", "1.5G", "12X", "12 M", " 12M", "12MB", "abc",
                          "99999999999999999999", "17179869184G"})
    EXPECT_FALSE(parse_memory_size(bad)) << bad;
  EXPECT_EQ(format_memory_size(512ull << 20), "512.0 MiB");
  EXPECT_EQ(memory_limit_argument((36ull << 20) + 1), "37M");
}

TEST(StreamingConvert, CliConvertsWithALimitAndSaysHowItSplitTheWork) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), whole = dir.file("whole.vxl"), limited = dir.file("limited.vxl");
  ASSERT_EQ(test::run_cli("synth '" + tck + "' --streamlines 4000").exit_code, 0);
  ASSERT_EQ(test::run_cli("convert '" + tck + "' '" + whole + "' --threads 2").exit_code, 0);
  auto r = test::run_cli("convert '" + tck + "' '" + limited + "' --threads 2 --memory-limit 20M");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("memory limit 20.0 MiB:"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(" 1 parts"), std::string::npos) << r.output;
  EXPECT_TRUE(test::slurp(whole) == test::slurp(limited));
  EXPECT_NE(test::run_cli("convert --help").output.find("--memory-limit"), std::string::npos);
}

// The same source and options give the same bytes on any machine: the worker threads (by default the machine's
// cores) change neither the data nor the provenance.
TEST(StreamingConvert, TheBytesDoNotDependOnTheThreads) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck");
  ASSERT_EQ(test::run_cli("synth '" + tck + "' --streamlines 1500").exit_code, 0);
  for (const char* threads : {"1", "3"})
    ASSERT_EQ(
        test::run_cli("convert '" + tck + "' '" + dir.file(std::string(threads) + ".vxl") + "' --threads " + threads)
            .exit_code,
        0);
  EXPECT_TRUE(test::slurp(dir.file("1.vxl")) == test::slurp(dir.file("3.vxl")));
}

TEST(StreamingConvert, CliRejectsBadSizesAsUsageErrors) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), out = dir.file("out.vxl");
  ASSERT_EQ(test::run_cli("synth '" + tck + "' --streamlines 10").exit_code, 0);
  for (const char* bad : {"abc", "12X", "-5M", "0", "1.5G", "M", "12MB", "99999999999999999999", "''"}) {
    auto r = test::run_cli("convert '" + tck + "' '" + out + "' --memory-limit " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.output;
    EXPECT_NE(r.output.find("not a memory size"), std::string::npos) << bad << ": " << r.output;
    EXPECT_FALSE(std::filesystem::exists(out)) << bad;
  }
}

TEST(StreamingConvert, CliFailsCleanlyWhenTheLimitIsTooSmall) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), out = dir.file("out.vxl"), trk = dir.file("in.trk");
  ASSERT_EQ(test::run_cli("synth '" + tck + "' --streamlines 2000").exit_code, 0);
  auto r = test::run_cli("convert '" + tck + "' '" + out + "' --memory-limit 8M");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("is too small"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("use --memory-limit"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
  std::ofstream(trk) << "x";
  r = test::run_cli("convert '" + trk + "' '" + out + "' --memory-limit 1G");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("TCK sources only"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
}

// The output is written piece by piece over many passes: a conversion killed at any moment must still
// leave nothing at the output path, nor a temporary file beside it.
TEST(StreamingConvert, AConversionKilledAtAnyMomentLeavesNoOutput) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), out = dir.file("out.vxl");
  ASSERT_EQ(test::run_cli("synth '" + tck + "' --streamlines 60000").exit_code, 0);
  const int killed_while_writing = test::kill_conversions(dir, {tck, out, "--memory-limit", "28M"}, out, 8);
  EXPECT_GE(killed_while_writing, 3) << "too few runs were killed while writing their output";
}

// The point of the option: the process's peak resident memory stays under the limit for a source larger than it. The
// peak is what `convert --verbose` reads from /proc/self/status (VmHWM): a parent's wait4() would also count this test
// process, which the child was a copy of until exec().
TEST(StreamingConvert, PeakResidentMemoryStaysUnderTheLimit) {
#if defined(VOXLINES_ADDRESS_SANITIZER)
  GTEST_SKIP() << "AddressSanitizer's shadow memory and quarantine make resident memory meaningless";
#else
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), out = dir.file("out.vxl");
  ASSERT_EQ(test::run_cli("synth '" + tck + "' --streamlines 80000").exit_code, 0);
  auto peak_kib = [&](const std::string& options) {
    auto r = test::run_cli("convert '" + tck + "' '" + out + "' --verbose --threads 2 " + options);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const std::size_t at = r.output.find("peak resident memory: ");
    EXPECT_NE(at, std::string::npos) << r.output;
    return at == std::string::npos ? 0ll : std::stoll(r.output.substr(at + 22));
  };
  const long long limit_kib = 40 * 1024;
  const long long limited = peak_kib("--memory-limit 40M");
  EXPECT_GT(static_cast<long long>(std::filesystem::file_size(tck)), 1024 * limit_kib)
      << "the source is too small to show anything";
  EXPECT_GT(limited, 0);
  EXPECT_LE(limited, limit_kib);
  EXPECT_TRUE(verify_vxl(out).valid);
#endif
}

}  // namespace
}  // namespace vxl

namespace vxl {
namespace {

// Found by fuzz_tck: a header line longer than the stream's first read must not be judged while cut (no
// colon yet) and refused with another error than the whole-file reader gives. Both must fail alike.
TEST(StreamingConvert, AHeaderLineCutByTheFirstReadFailsAsInMemory) {
  ScratchDir dir;
  const std::string tck = dir.file("long_key.tck");
  {
    std::ofstream f(tck, std::ios::binary);
    f << "mrtrix tracks\n" << std::string(70000, 'k') << ": v\ndatatype: Float32LE\nfile: . 5\nEND\n";
  }
  auto whole = test::run_cli("convert '" + tck + "' '" + dir.file("a.vxl") + "'");
  auto limited = test::run_cli("convert '" + tck + "' '" + dir.file("b.vxl") + "' --memory-limit 64M");
  EXPECT_EQ(whole.exit_code, 3) << whole.output;
  EXPECT_EQ(limited.exit_code, whole.exit_code) << limited.output;
  EXPECT_NE(whole.output.find("data offset points inside the header"), std::string::npos) << whole.output;
  EXPECT_EQ(limited.output, whole.output);
}

}  // namespace
}  // namespace vxl
