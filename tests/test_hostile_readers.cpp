// Hostile source files (tests/hostile_inputs.h writes them): each must be refused with a vxl::Error of
// the right kind, or read with a warning where data would otherwise be lost silently.
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "converter/readers/nifti_image.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/read_tsf.h"
#include "converter/readers/tck_stream.h"
#include "converter/share/share_folder.h"
#include "format/base/error.h"
#include "tests/hostile_inputs.h"
#include "tests/nifti_test_files.h"
#include "tests/test_support.h"

namespace {

namespace hostile = vxl::test::hostile;
using hostile::error_of;
using vxl::test::has_warning;
using vxl::test::ScratchDir;

// ---- row 1: a TRX member name with a component count beyond 64 bits ----

TEST(HostileTrx, ComponentCountBeyond64BitsIsMalformedAndNamesTheMember) {
  ScratchDir dir;
  const std::string p = dir.file("c.trx");
  hostile::trx_huge_component_count(p);
  const vxl::Error e = error_of([&] { (void)vxl::read_trx(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
  EXPECT_NE(std::string(e.what()).find("dps/c.99999999999999999999.float32"), std::string::npos) << e.what();
  const auto cli = vxl::test::run_cli("convert " + p + " " + dir.file("o.vxl"));
  EXPECT_EQ(cli.exit_code, 3) << cli.output;
}

// ---- row 5: .trk.gz bombs, zero-point records ----

TEST(HostileTrk, ZeroPointRecordIsMalformed) {
  ScratchDir dir;
  const std::string p = dir.file("z.trk");
  hostile::write_file(p,
                      hostile::trk_header() + hostile::trk_record(2) + hostile::trk_record(0) + hostile::trk_record(1));
  const vxl::Error e = error_of([&] { (void)vxl::read_trk(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
  EXPECT_EQ(e.offset(), std::optional<std::uint64_t>(1000 + 4 + 2 * 12)) << e.what();
  EXPECT_NE(std::string(e.what()).find("no points"), std::string::npos) << e.what();
}

// 64 MiB of zeros after the header (a 70 KiB file): refused at the first record, before the rest is inflated.
TEST(HostileTrk, GzipOfZerosIsRefusedAtTheFirstRecord) {
  ScratchDir dir;
  const std::string p = dir.file("zeros.trk.gz");
  hostile::trk_gz_zeros(p, 64);
  const vxl::Error e = error_of([&] { (void)vxl::read_trk(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
  EXPECT_EQ(e.offset(), std::optional<std::uint64_t>(1000)) << e.what();
  const auto cli = vxl::test::run_cli("convert " + p + " " + dir.file("o.vxl"));
  EXPECT_EQ(cli.exit_code, 3) << cli.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("o.vxl")));
}

// Valid-looking records that deflate ~1000:1: refused once the stream passes 100x the file's size (+1 MiB),
// i.e. after about 2 MiB of the 8 MiB it holds.
TEST(HostileTrk, GzipThatInflatesBeyondTheRatioCapIsRefused) {
  ScratchDir dir;
  const std::string p = dir.file("bomb.trk.gz");
  hostile::trk_gz_record_bomb(p, 8);
  ASSERT_LT(std::filesystem::file_size(p), 20000u);
  const vxl::Error e = error_of([&] { (void)vxl::read_trk(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Unsupported) << e.what();
  EXPECT_NE(std::string(e.what()).find("decompression bomb"), std::string::npos) << e.what();
}

// Concatenated gzip members are one gzip stream (gzip -d and Python read them so): accepted.
TEST(HostileTrk, ConcatenatedGzipMembersAreOneStream) {
  ScratchDir dir;
  const std::string p = dir.file("two.trk.gz");
  hostile::write_file(
      p, hostile::gzip(hostile::trk_header() + hostile::trk_record(2)) + hostile::gzip(hostile::trk_record(3)));
  const vxl::Tractogram t = vxl::read_trk(p);
  EXPECT_EQ(t.streamline_count(), 2u);
  EXPECT_EQ(t.point_count(), 5u);
}

// ---- row 7: a gzip stream without its end, or with something after it ----

TEST(HostileTrk, GzipCutAtARecordBoundaryIsTruncated) {
  ScratchDir dir;
  for (std::int32_t n_count : {0, 3}) {
    SCOPED_TRACE(n_count);
    const std::string p = dir.file("cut" + std::to_string(n_count) + ".trk.gz");
    hostile::trk_gz_cut_at_record(p, n_count);
    const vxl::Error e = error_of([&] { (void)vxl::read_trk(p); });
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

TEST(HostileTrk, GarbageAfterTheGzipStreamIsMalformed) {
  ScratchDir dir;
  const std::string p = dir.file("tail.trk.gz");
  hostile::trk_gz_with_tail(p, "garbage");
  const vxl::Error e = error_of([&] { (void)vxl::read_trk(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
  EXPECT_EQ(e.offset(), std::optional<std::uint64_t>(std::filesystem::file_size(p) - 7)) << e.what();
  const auto cli = vxl::test::run_cli("convert " + p + " " + dir.file("o.vxl"));
  EXPECT_EQ(cli.exit_code, 3) << cli.output;
}

// Zero padding after the stream is skipped, as gzip and Python do, but said.
TEST(HostileTrk, ZeroPaddingAfterTheGzipStreamIsWarned) {
  ScratchDir dir;
  const std::string p = dir.file("pad.trk.gz");
  hostile::trk_gz_with_tail(p, std::string(10, '\0'));
  const vxl::Tractogram t = vxl::read_trk(p);
  EXPECT_EQ(t.streamline_count(), 2u);
  EXPECT_TRUE(has_warning(t.source.warnings, "10 zero bytes of padding"))
      << ::testing::PrintToString(t.source.warnings);
}

// ---- row 6: a deflated TRX member that inflates far beyond what header.json allows ----

// Its directory says 16 MiB where NB_STREAMLINES = 3 allows 32 bytes: refused before inflating.
TEST(HostileTrx, DeclaredSizeBeyondTheHeaderCountsIsRefusedBeforeInflating) {
  ScratchDir dir;
  const std::string p = dir.file("bomb.trx");
  hostile::trx_offsets_bomb(p, 16, /*honest=*/true);
  const vxl::Error e = error_of([&] { (void)vxl::read_trx(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
  EXPECT_NE(std::string(e.what()).find("offsets.uint64: its zip entry declares 16777216 bytes, more than the 32"),
            std::string::npos)
      << e.what();
}

// Its directory says 32 bytes but the data inflates to 16 MiB: inflating stops just past 32.
TEST(HostileTrx, MemberInflatingPastItsDeclaredSizeIsStopped) {
  ScratchDir dir;
  const std::string p = dir.file("liar.trx");
  hostile::trx_offsets_bomb(p, 16, /*honest=*/false);
  const vxl::Error e = error_of([&] { (void)vxl::read_trx(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
  EXPECT_NE(std::string(e.what()).find("offsets.uint64: zip entry inflates to more than the 32 bytes"),
            std::string::npos)
      << e.what();
}

// A dps member of the wrong declared size is skipped, as before, but without inflating it.
TEST(HostileTrx, ValueMemberOfTheWrongDeclaredSizeIsSkippedUnread) {
  ScratchDir dir;
  const std::string p = dir.file("dps.trx");
  vxl::test::write_zip(p, hostile::trx_entries(3, {vxl::test::deflated_zeros_entry("dps/w.float32", 16u << 20)}));
  const vxl::Tractogram t = vxl::read_trx(p);
  EXPECT_TRUE(t.streamline_values.empty());
  EXPECT_TRUE(has_warning(t.source.warnings, "dps/w.float32: holds 16777216 bytes, expected 3 x 1 x 4; ignored"))
      << ::testing::PrintToString(t.source.warnings);
}

// ---- rows 8, 9: TSF values beyond float32, a wrong count ----

TEST(HostileTsf, Float64ValueBeyondFloat32IsRefusedWithItsOffset) {
  ScratchDir dir;
  const std::string p = dir.file("big.tsf");
  hostile::tsf_float64_out_of_range(p);
  const vxl::Error e = error_of([&] { (void)vxl::read_tsf(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
  EXPECT_EQ(e.offset(), std::optional<std::uint64_t>(std::filesystem::file_size(p) - 5 * 8)) << e.what();
  EXPECT_NE(std::string(e.what()).find("float32 range"), std::string::npos) << e.what();
}

TEST(HostileTsf, WrongCountIsWarnedLikeTck) {
  ScratchDir dir;
  const std::string p = dir.file("count.tsf");
  hostile::tsf_wrong_count(p);
  const vxl::TrackScalars s = vxl::read_tsf(p);
  EXPECT_EQ(s.offsets.size(), 4u);
  EXPECT_TRUE(has_warning(s.warnings, "header count 99 disagrees with the data (3 streamlines)"))
      << ::testing::PrintToString(s.warnings);
}

// ---- row 13: TCK data lost silently, a negative count ----

// read_tck and TckStream must say the same.
std::vector<std::string> tck_warnings(const std::string& p) {
  const vxl::Tractogram t = vxl::read_tck(p);
  vxl::TckStream stream(p, 1 << 20, 12);
  vxl::Tractogram batch;
  while (stream.next(batch, 2)) {
  }
  EXPECT_EQ(stream.source().warnings, t.source.warnings);
  return t.source.warnings;
}

TEST(HostileTck, InfInOneCoordinateIsWarned) {
  ScratchDir dir;
  const std::string p = dir.file("inf.tck");
  hostile::tck_inf_in_one_coordinate(p);
  EXPECT_EQ(vxl::read_tck(p).streamline_count(), 1u);
  const auto w = tck_warnings(p);
  EXPECT_TRUE(has_warning(w, "not the terminator (Inf, Inf, Inf)")) << ::testing::PrintToString(w);
  EXPECT_TRUE(has_warning(w, "36 bytes after the Inf terminator ignored")) << ::testing::PrintToString(w);
}

TEST(HostileTck, DataAfterTheTerminatorIsWarned) {
  ScratchDir dir;
  const std::string p = dir.file("after.tck");
  hostile::tck_data_after_terminator(p);
  const auto w = tck_warnings(p);
  EXPECT_TRUE(has_warning(w, "36 bytes after the Inf terminator ignored")) << ::testing::PrintToString(w);
  const auto cli = vxl::test::run_cli("convert " + p + " " + dir.file("o.vxl"));
  EXPECT_EQ(cli.exit_code, 0) << cli.output;
  EXPECT_NE(cli.output.find("36 bytes after the Inf terminator ignored"), std::string::npos) << cli.output;
}

TEST(HostileTck, NegativeCountIsQuotedAsWritten) {
  ScratchDir dir;
  const std::string p = dir.file("neg.tck");
  hostile::tck_negative_count(p);
  const auto w = tck_warnings(p);
  EXPECT_TRUE(has_warning(w, "header count '-5' is not a number of streamlines")) << ::testing::PrintToString(w);
  EXPECT_FALSE(has_warning(w, "18446744073709551611")) << ::testing::PrintToString(w);
}

// ---- row 12: a FIFO as input must not hang ----

// Through the CLI under `timeout`, so that a reader that blocks on the FIFO fails the test (exit 124)
// ---- NIfTI images (.nii.gz read through the .trk.gz rules) ----

// 64 x 64 x 64 int16 voxels of small pseudo-random values: they compress, into Huffman-coded blocks
// that a flipped byte damages.
std::string nifti_noise() {
  std::string data(64 * 64 * 64 * 2, '\0');
  std::uint32_t x = 12345;
  for (std::size_t i = 0; i < data.size(); i += 2) {
    x = x * 1664525u + 1013904223u;
    data[i] = static_cast<char>((x >> 24) & 0x0F);
  }
  return vxl::test::nifti1_bytes({64, 64, 64}, 4, 16, data);
}

// Exit 3 naming the file and where zlib failed, having allocated only what it had read.
TEST(NiftiImage, DamagedGzipIsExit3) {
  ScratchDir dir;
  std::string gz = hostile::gzip(nifti_noise());
  ASSERT_GT(gz.size(), 100000u);
  for (std::size_t at = 70000; at < 70016; ++at) gz[at] = static_cast<char>(~gz[at]);
  const std::string p = dir.file("damaged.nii.gz");
  hostile::write_file(p, gz);
  const vxl::Error e = error_of([&] { (void)vxl::read_volume_image(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
  ASSERT_TRUE(e.offset().has_value()) << e.what();
  EXPECT_GE(*e.offset(), 70000u) << e.what();
  EXPECT_NE(std::string(e.what()).find("corrupt gzip stream"), std::string::npos) << e.what();
}

// The same damage under a header claiming 8 GiB (1024^3 float64): exit 3 too, having allocated nothing for
// the claim.
TEST(NiftiImage, DamagedGzipClaimingGigabytesIsExit3) {
  ScratchDir dir;
  std::string nii = nifti_noise();
  const std::int16_t dims[3] = {1024, 1024, 1024};
  std::memcpy(nii.data() + 42, dims, sizeof dims);
  const std::int16_t float64[2] = {64, 64};
  std::memcpy(nii.data() + 70, float64, sizeof float64);
  std::string gz = hostile::gzip(nii);
  for (std::size_t at = 70000; at < 70016; ++at) gz[at] = static_cast<char>(~gz[at]);
  const std::string p = dir.file("claims8g.nii.gz");
  hostile::write_file(p, gz);
  const vxl::Error e = error_of([&] { (void)vxl::read_volume_image(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
  EXPECT_NE(std::string(e.what()).find("corrupt gzip stream"), std::string::npos) << e.what();
}

// 128 MiB of zeros (a 130 KB file) claimed by a 512^3 uint8 header: refused before inflating, where the
// whole image would have been read at several times its size.
TEST(NiftiImage, GzipBombIsRefusedFromItsHeader) {
  ScratchDir dir;
  const std::string zeros = hostile::gzip(std::string(1u << 20, '\0'));
  std::string gz = hostile::gzip(vxl::test::nifti1_bytes({512, 512, 512}, 2, 8, ""));
  for (int i = 0; i < 128; ++i) gz += zeros;
  const std::string p = dir.file("bomb.nii.gz");
  hostile::write_file(p, gz);
  ASSERT_LT(std::filesystem::file_size(p), 200000u);
  const vxl::Error e = error_of([&] { (void)vxl::read_volume_image(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Unsupported) << e.what();
  EXPECT_NE(std::string(e.what()).find("decompression bomb"), std::string::npos) << e.what();
  // A mask of zeros and a few ones compresses a thousandfold too: 64 MiB pass whatever the ratio.
  std::string mask(256 * 256 * 256, '\0');
  mask[1000] = 1;
  const std::string q = dir.file("mask.nii.gz");
  hostile::write_file(q, hostile::gzip(vxl::test::nifti1_bytes({256, 256, 256}, 2, 8, mask)));
  ASSERT_LT(std::filesystem::file_size(q), 100000u);
  const vxl::VolumeImage m = vxl::read_volume_image(q);
  EXPECT_EQ(m.values[1000], 1.0f);
}

TEST(NiftiImage, GzipWithoutItsTrailerOrWithJunkAfterIsExit3) {
  ScratchDir dir;
  const std::string nii = vxl::test::nifti1_bytes({2, 2, 2}, 2, 8, std::string(8, '\1'));
  const std::string cut = dir.file("cut.nii.gz"), junk = dir.file("junk.nii.gz"), pad = dir.file("pad.nii.gz");
  hostile::write_file(cut, hostile::gzip(nii, /*finish=*/false));
  hostile::write_file(junk, hostile::gzip(nii) + "garbage");
  hostile::write_file(pad, hostile::gzip(nii) + std::string(10, '\0'));
  const vxl::Error c = error_of([&] { (void)vxl::read_volume_image(cut); });
  EXPECT_EQ(c.kind(), vxl::ErrorKind::Input) << c.what();
  EXPECT_NE(std::string(c.what()).find("without its end-of-stream marker"), std::string::npos) << c.what();
  const vxl::Error j = error_of([&] { (void)vxl::read_volume_image(junk); });
  EXPECT_EQ(j.kind(), vxl::ErrorKind::Input) << j.what();
  EXPECT_EQ(j.offset(), std::optional<std::uint64_t>(std::filesystem::file_size(junk) - 7)) << j.what();
  EXPECT_EQ(vxl::read_volume_image(pad).values.size(), 8u);  // zero padding, as gzip and .trk.gz allow
}

TEST(NiftiImage, BinaryDatatypeIsUnsupportedNamingIt) {
  ScratchDir dir;
  const std::string p = dir.file("bits.nii");
  hostile::write_file(p, vxl::test::nifti1_bytes({8, 1, 1}, 1, 1, std::string(1, '\xFF')));
  const vxl::Error e = error_of([&] { (void)vxl::read_volume_image(p); });
  EXPECT_EQ(e.kind(), vxl::ErrorKind::Unsupported) << e.what();
  EXPECT_NE(std::string(e.what()).find("datatype 1 (BINARY)"), std::string::npos) << e.what();
}

TEST(NiftiImage, AbsurdTransformsAreExit3) {
  ScratchDir dir;
  const float inf = std::numeric_limits<float>::infinity();
  const std::pair<std::array<float, 12>, const char*> cases[] = {
      {{1e30f, 0, 0, 0, 0, 1e30f, 0, 0, 0, 0, 1e30f, 0}, "1e+30 mm long"},
      {{1e-9f, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}, "1e-09 mm long"},
      {{1, 0, 0, 2e6f, 0, 1, 0, 0, 0, 0, 1, 0}, "puts voxel 0,0,0 at 2e+06"},
      {{1, 0, 0, inf, 0, 1, 0, 0, 0, 0, 1, 0}, "not finite"},
      {{1, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0}, "singular"},  // the third axis along the first
  };
  for (const auto& [sform, says] : cases) {
    const std::string p = dir.file("affine.nii");
    hostile::write_file(p, vxl::test::nifti1_bytes({2, 2, 2}, 2, 8, std::string(8, '\1'), sform));
    const vxl::Error e = error_of([&] { (void)vxl::read_volume_image(p); });
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
    EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << says << ": " << e.what();
    EXPECT_NE(std::string(e.what()).find("1e-06 to 10000 mm"), std::string::npos) << e.what();
  }
}

// instead of hanging it.
TEST(HostileInput, FifoIsRefusedNotWaitedOn) {
  ScratchDir dir;
  for (const char* name :
       {"in.tck", "in.trk", "in.trk.gz", "in.trx", "in.tsf", "in.vtk", "in.vtp", "in.vxl", "in.vxlz"})
    hostile::fifo(dir.file(name));
  vxl::test::write_mrtrix_file(dir.file("ok.tck"), "mrtrix tracks", "Float32LE", "");
  // share reads its input only once it has a web viewer to copy: a stand-in folder of its files.
  std::filesystem::create_directories(dir.file("web"));
  for (const char* name : vxl::kWebViewerFiles) std::ofstream(dir.file("web") + "/" + name) << name;
  const std::string out = dir.file("o.vxl");
  const std::vector<std::string> commands = {
      "convert " + dir.file("in.tck") + " " + out,
      "convert " + dir.file("in.tck") + " " + out + " --memory-limit 64M",
      "convert " + dir.file("in.trk") + " " + out,
      "convert " + dir.file("in.trk.gz") + " " + out,
      "convert " + dir.file("in.trx") + " " + out,
      "convert " + dir.file("ok.tck") + " " + out + " --tsf " + dir.file("in.tsf"),
      "convert " + dir.file("in.vtk") + " " + out,
      "convert " + dir.file("in.vtp") + " " + out,
      "info " + dir.file("in.vxl"),
      "info " + dir.file("in.vxlz"),
      "unpack " + dir.file("in.vxlz") + " " + out,
      "export " + dir.file("in.vxl") + " " + dir.file("o.tck"),
      "share " + dir.file("in.vxl") + " " + dir.file("shared") + " --web-viewer " + dir.file("web"),
      "share " + dir.file("in.vxlz") + " " + dir.file("shared") + " --web-viewer " + dir.file("web"),
  };
  for (const std::string& c : commands) {
    SCOPED_TRACE(c);
    const auto r = vxl::test::run_program("timeout 20", std::string(VOXLINES_CLI) + " " + c);
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_TRUE(r.output.find("is a FIFO") != std::string::npos ||
                r.output.find("not a regular file") != std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));
    EXPECT_FALSE(std::filesystem::exists(dir.file("shared")));
  }
}

}  // namespace
