// Golden bytes: files written once from a pinned input (tests/data/golden/, scripts/regenerate-golden) and
// committed. The writers must reproduce them byte for byte, and the readers must decode them to the input's
// coordinates, so that a writer and a reader wrong in the same way cannot pass by agreeing with each other.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "converter/convert/streaming_convert.h"
#include "converter/readers/read_tractogram.h"
#include "format/voxel_voxlines.h"
#include "format/vxl_file.h"
#include "format/vxl_streamlines.h"
#include "format/vxl_verify.h"
#include "format/vxlz_package.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::q;
using test::run_cli;
using test::ScratchDir;
using test::slurp;

std::string golden(const std::string& name) { return std::string(VOXLINES_TEST_DATA_DIR) + "/golden/" + name; }

// The pinned options: the same as scripts/regenerate-golden's.
const std::string kPinnedOptions = " --voxel-size 8 --levels 2 --threads 1";
const std::string kRegenerate =
    " (when the change of bytes is intended: scripts/regenerate-golden, and review the diff of tests/data/golden/)";

// Byte-for-byte equality, reporting the first differing offset rather than two dumps.
void expect_same_bytes(const std::string& written, const std::string& golden_path) {
  const std::vector<char> a = slurp(written), b = slurp(golden_path);
  ASSERT_EQ(a.size(), b.size()) << written << " vs " << golden_path << kRegenerate;
  for (std::size_t i = 0; i < a.size(); ++i)
    ASSERT_EQ(a[i], b[i]) << "first difference at byte " << i << " of " << golden_path << kRegenerate;
}

// The same sections in the same order, each payload the same bytes, except PROV, whose JSON must be the same once
// `converter.threads` is left out of both: earlier converters recorded their worker threads, which the older
// golden packages carry in the PROV they ship.
void expect_same_sections_but_threads(const std::string& written, const std::string& golden_path) {
  const VxlFile a = VxlFile::open(written), b = VxlFile::open(golden_path);
  ASSERT_EQ(a.sections().size(), b.sections().size()) << kRegenerate;
  for (std::size_t i = 0; i < a.sections().size(); ++i) {
    const SectionEntry &x = a.sections()[i], &y = b.sections()[i];
    const std::string id(x.id, 4);
    ASSERT_EQ(id, std::string(y.id, 4)) << kRegenerate;
    const auto bytes_of = [](const VxlFile& f, const SectionEntry& e) {
      return std::string(reinterpret_cast<const char*>(f.bytes().data() + e.offset), e.size);
    };
    if (id != "PROV") {
      EXPECT_EQ(bytes_of(a, x), bytes_of(b, y)) << "section " << id << kRegenerate;
      continue;
    }
    nlohmann::json pa = nlohmann::json::parse(bytes_of(a, x)), pb = nlohmann::json::parse(bytes_of(b, y));
    pa["converter"].erase("threads");
    pb["converter"].erase("threads");
    EXPECT_EQ(pa, pb) << kRegenerate;
  }
}

struct Streamlines {
  std::vector<std::vector<float>> xyz;
};

Streamlines decode_vxl(const std::string& path) {
  const VxlFile file = VxlFile::open(path);
  Streamlines out;
  WalkCallbacks callbacks;
  callbacks.streamline = [&](std::uint64_t index, std::span<const float> xyz) {
    EXPECT_EQ(index, out.xyz.size());
    out.xyz.emplace_back(xyz.begin(), xyz.end());
  };
  walk_streamlines(file, callbacks);
  return out;
}

Streamlines pinned_input() {
  const Tractogram t = read_tractogram(golden("pinned.tck"));
  Streamlines out;
  for (std::size_t s = 0; s < t.streamline_count(); ++s)
    out.xyz.emplace_back(t.positions.begin() + 3 * t.offsets[s], t.positions.begin() + 3 * t.offsets[s + 1]);
  return out;
}

// Every coordinate of `decoded` within `tolerance` mm of the pinned input's (0: bit for bit).
void expect_coordinates(const Streamlines& decoded, double tolerance) {
  const Streamlines input = pinned_input();
  ASSERT_EQ(decoded.xyz.size(), input.xyz.size());
  double worst = 0;
  for (std::size_t s = 0; s < input.xyz.size(); ++s) {
    ASSERT_EQ(decoded.xyz[s].size(), input.xyz[s].size()) << "streamline " << s;
    for (std::size_t i = 0; i < input.xyz[s].size(); ++i)
      worst = std::max(worst, std::abs(double(decoded.xyz[s][i]) - double(input.xyz[s][i])));
  }
  EXPECT_LE(worst, tolerance);
}

TEST(GoldenBytes, TheCommittedFilesAreTheOnesListedInTheirChecksums) {
  const std::string command =
      "cd " + q(std::string(VOXLINES_TEST_DATA_DIR) + "/golden") + " && sha256sum --check --strict --quiet SHA256SUMS";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
}

TEST(GoldenBytes, TheInputIsTheOnePinned) {
  // Known coordinates, read with an independent reader (nibabel) when the input was pinned: the first
  // point of the first streamline and the last of the last one.
  const Streamlines input = pinned_input();
  ASSERT_EQ(input.xyz.size(), 8u);
  EXPECT_EQ(input.xyz[0].size(), 3u * 32);
  EXPECT_EQ(input.xyz[7].size(), 3u * 76);
  EXPECT_FLOAT_EQ(input.xyz[0][0], 22.180646896362305f);
  EXPECT_FLOAT_EQ(input.xyz[0][1], -22.12089729309082f);
  EXPECT_FLOAT_EQ(input.xyz[0][2], 23.863332748413086f);
  const std::vector<float>& last = input.xyz[7];
  EXPECT_FLOAT_EQ(last[last.size() - 3], -9.0084228515625f);
  EXPECT_FLOAT_EQ(last[last.size() - 2], -15.260669708251953f);
  EXPECT_FLOAT_EQ(last[last.size() - 1], -29.45517349243164f);
}

TEST(GoldenBytes, ConvertWritesThePackedFile) {
  ScratchDir dir;
  const auto r = run_cli("convert " + q(golden("pinned.tck")) + " " + q(dir.file("packed.vxl")) + kPinnedOptions);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_same_bytes(dir.file("packed.vxl"), golden("packed.vxl"));
}

TEST(GoldenBytes, ConvertWritesTheFloat32File) {
  ScratchDir dir;
  const auto r = run_cli("convert " + q(golden("pinned.tck")) + " " + q(dir.file("float32.vxl")) + kPinnedOptions +
                         " --positions float32");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_same_bytes(dir.file("float32.vxl"), golden("float32.vxl"));
}

TEST(GoldenBytes, AStreamedConversionWritesThePackedFile) {
  ScratchDir dir;
  ConvertSettings settings;  // the pinned options
  settings.voxel_size = 8;
  settings.levels = 2;
  settings.threads = 1;
  settings.memory_limit = 20 * (std::uint64_t(1) << 20);  // the smallest limit the program accepts
  StreamingTuning tuning;
  tuning.order_chunk_bytes = 256;  // orders built and written a few voxels at a time
  const ConvertSummary s = convert_streaming(golden("pinned.tck"), dir.file("streamed.vxl"), settings, tuning);
  EXPECT_GE(s.passes, 3u);  // scan, plan, place: the source was streamed, not held
  expect_same_bytes(dir.file("streamed.vxl"), golden("packed.vxl"));
}

TEST(GoldenBytes, PackWritesThePackage) {
  ScratchDir dir;
  const auto r = run_cli("pack " + q(golden("packed.vxl")) + " " + q(dir.file("package.vxlz")) + " --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_same_bytes(dir.file("package.vxlz"), golden("package.vxlz"));
}

TEST(GoldenBytes, UnpackWritesTheUnpackedFile) {
  ScratchDir dir;
  const auto r = run_cli("unpack " + q(golden("package.vxlz")) + " " + q(dir.file("unpacked.vxl")) + " --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_same_bytes(dir.file("unpacked.vxl"), golden("unpacked.vxl"));
}

// Packages of older versions (frozen) still unpack, to the very file the package of today unpacks to: 2.0 ships the
// points in streamline order (predictor 1), 2.3 level by level without a checksum per chunk; the order the points
// travel in and the chunks' checksums change nothing else.
TEST(GoldenBytes, PackagesOfVersions20And23UnpackAsTheCurrentOne) {
  const VxlzFile now = VxlzFile::open(golden("package.vxlz"));
  EXPECT_EQ(now.header().version_minor, kVxlzVersionMinorChunkChecksums);
  EXPECT_EQ(now.pack().predictor, kVxlzPredictorLinearLevelOrder);
  EXPECT_EQ(now.pack().level_count, 2u);
  EXPECT_TRUE(now.has_chunk_checksums());
  struct Older {
    const char* name;
    std::uint16_t minor;
    std::uint32_t predictor;
  };
  for (const Older& older : {Older{"package-2.0.vxlz", 0, kVxlzPredictorLinear},
                             Older{"package-2.3.vxlz", kVxlzVersionMinorLevelOrder, kVxlzPredictorLinearLevelOrder}}) {
    SCOPED_TRACE(older.name);
    ScratchDir dir;
    const VxlzFile package = VxlzFile::open(golden(older.name));
    EXPECT_EQ(package.header().version_minor, older.minor);
    EXPECT_EQ(package.pack().predictor, older.predictor);
    EXPECT_FALSE(package.has_chunk_checksums());
    // Named as the current one: the unpacked file's provenance names its package.
    std::filesystem::copy_file(golden(older.name), dir.file("package.vxlz"));
    const auto r =
        run_cli("unpack " + q(dir.file("package.vxlz")) + " " + q(dir.file("unpacked.vxl")) + " --threads 1");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    expect_same_sections_but_threads(dir.file("unpacked.vxl"), golden("unpacked.vxl"));
  }
}

TEST(GoldenBytes, TheFloat32FileDecodesToTheInputBitForBit) {
  expect_coordinates(decode_vxl(golden("float32.vxl")), 0);
}

TEST(GoldenBytes, ThePackedFileDecodesWithinItsBound) {
  // 10 bits per axis over 8 mm voxels: within 4.5 um per axis (spec §5.4).
  expect_coordinates(decode_vxl(golden("packed.vxl")), 0.0045);
}

TEST(GoldenBytes, TheUnpackedFileDecodesWithinThePackagesBoundAndARepack) {
  const VxlzFile package = VxlzFile::open(golden("package.vxlz"));
  EXPECT_EQ(package.meta().streamline_count, 8u);
  EXPECT_EQ(package.meta().point_count, 418u);
  // The package's stated bound (against the packed file) plus the packed file's own and the re-pack's.
  expect_coordinates(decode_vxl(golden("unpacked.vxl")), package.pack().error_bound + 2 * 0.0045);
}

// The lengths (SLEN) are the pinned input's, measured here independently (std::hypot per segment): the same in
// the packed and the float32 file, since both come from the source points, not from the packed ones.
TEST(GoldenBytes, TheLengthsAreTheInputsOwn) {
  const Streamlines input = pinned_input();
  const VxlFile packed = VxlFile::open(golden("packed.vxl")), float32 = VxlFile::open(golden("float32.vxl"));
  ASSERT_EQ(packed.streamline_lengths().size(), input.xyz.size());
  ASSERT_EQ(float32.streamline_lengths().size(), input.xyz.size());
  for (std::size_t s = 0; s < input.xyz.size(); ++s) {
    const std::vector<float>& p = input.xyz[s];
    double length = 0;
    for (std::size_t i = 3; i < p.size(); i += 3)
      length += std::hypot(double(p[i]) - p[i - 3], double(p[i + 1]) - p[i - 2], double(p[i + 2]) - p[i - 1]);
    EXPECT_GT(length, 10.0) << "streamline " << s;
    EXPECT_NEAR(packed.streamline_lengths()[s], length, 1e-6 * length) << "streamline " << s;
    EXPECT_EQ(packed.streamline_lengths()[s], float32.streamline_lengths()[s]) << "streamline " << s;
  }
}

// A file of version 2.1 (frozen: whole-byte orders in ORDR, no VXIX) still opens and verifies, and reads as the
// same orders, points and voxel lists as the pinned input's file of today.
TEST(GoldenBytes, AFileOfVersion21ReadsAsTheCurrentOne) {
  const VxlFile old_file = VxlFile::open(golden("packed-2.1.vxl")), now = VxlFile::open(golden("packed.vxl"));
  EXPECT_EQ(old_file.header().version_major, 2);
  EXPECT_EQ(old_file.header().version_minor, 1);
  EXPECT_EQ(now.header().version_minor, 4);
  EXPECT_EQ(old_file.order_packing(), OrderPacking::Bytes);
  EXPECT_EQ(now.order_packing(), OrderPacking::Bits);
  EXPECT_LT(now.order_bytes().size(), old_file.order_bytes().size());
  EXPECT_TRUE(old_file.voxel_index_first().empty());
  ASSERT_FALSE(now.voxel_index_first().empty());
  EXPECT_TRUE(old_file.streamline_lengths().empty());
  EXPECT_TRUE(verify_vxl(golden("packed-2.1.vxl")).valid) << verify_vxl(golden("packed-2.1.vxl")).problem;
  EXPECT_TRUE(verify_vxl(golden("packed.vxl")).valid) << verify_vxl(golden("packed.vxl")).problem;

  ASSERT_EQ(old_file.voxels().size(), now.voxels().size());
  ASSERT_EQ(old_file.level_count(), now.level_count());
  std::uint64_t entries = 0;
  for (std::size_t i = 0; i < now.voxels().size(); ++i)
    for (std::uint32_t level = 0; level < now.level_count(); ++level)
      for (std::uint32_t k = 0; k < now.meta().stored_order_count; ++k) {
        const OrderView a = old_file.order(i, k, level), b = now.order(i, k, level);
        ASSERT_EQ(a.count, b.count);
        EXPECT_EQ(a.bits % 8, 0u);
        EXPECT_LE(b.bits, a.bits);
        for (std::uint32_t n = 0; n < a.count; ++n, ++entries)
          ASSERT_EQ(a[n], b[n]) << "voxel " << i << " level " << level << " order " << k << " entry " << n;
      }
  EXPECT_GT(entries, 400u);
  EXPECT_EQ(decode_vxl(golden("packed-2.1.vxl")).xyz, decode_vxl(golden("packed.vxl")).xyz);

  // The lists built from the old file's tables are the ones the new file carries.
  const std::optional<VoxelVoxlines> built = VoxelVoxlines::of_file(old_file), mapped = VoxelVoxlines::of_file(now);
  ASSERT_TRUE(built && mapped);
  EXPECT_FALSE(built->from_file());
  EXPECT_TRUE(mapped->from_file());
  for (std::size_t i = 0; i < now.voxels().size(); ++i) {
    const auto a = built->of_voxel(i), b = mapped->of_voxel(i);
    ASSERT_EQ(a.size(), b.size()) << "voxel " << i;
    for (std::size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a[k].word, b[k].word) << "voxel " << i << " entry " << k;
  }
}

}  // namespace
}  // namespace vxl
