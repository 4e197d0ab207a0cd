// `voxlines share`: the folder appears only when complete, with the web viewer's files, the tractogram (a .vxl,
// or a .vxlz as it is or unpacked) and share.json naming it; every refusal leaves no folder and no temporary one beside
// it. The web viewer here is a stand-in folder (its files' contents do not matter to share); tests/web checks the real
// one in a browser.
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "converter/package/unpack.h"
#include "converter/share/share_folder.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_layout.h"
#include "format/vxl_level_image.h"
#include "test_support.h"
#include "tests/hostile_inputs.h"
#include "tests/reseal_checksums.h"

namespace vxl {
namespace {

namespace fs = std::filesystem;

// A folder holding a file of each name share copies.
std::string stand_in_web_viewer(const test::ScratchDir& dir) {
  const std::string viewer = dir.file("web");
  fs::create_directories(viewer);
  for (const char* name : kWebViewerFiles) std::ofstream(viewer + "/" + name) << name;
  return viewer;
}

// Nothing in the scratch folder but what the test made: no temporary folder left by share.
int entries_named_part(const test::ScratchDir& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir.path()))
    n += e.path().filename().string().find(".part-") != std::string::npos;
  return n;
}

struct SharedTractogram {
  test::ScratchDir dir;
  std::string tck = dir.file("in.tck"), vxl = dir.file("in.vxl"), viewer = stand_in_web_viewer(dir);
  SharedTractogram() {
    EXPECT_EQ(test::run_cli("synth " + test::q(tck) + " --streamlines 300").exit_code, 0);
    EXPECT_EQ(test::run_cli("convert " + test::q(tck) + " " + test::q(vxl)).exit_code, 0);
  }
  test::CommandResult share(const std::string& in, const std::string& out, const std::string& more = "") const {
    return test::run_cli("share " + test::q(in) + " " + test::q(out) + " --web-viewer " + test::q(viewer) + more);
  }
};

TEST(Share, WritesTheViewerTheVxlAndShareJson) {
  SharedTractogram t;
  const std::string out = t.dir.file("shared");
  const auto r = t.share(t.vxl, out, " --title 'Subject 7'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* name : kWebViewerFiles) EXPECT_EQ(test::slurp(out + "/" + name).size(), std::string(name).size());
  EXPECT_EQ(test::slurp(out + "/in.vxl"), test::slurp(t.vxl));
  const auto share = nlohmann::json::parse(test::slurp(out + "/share.json"));
  EXPECT_EQ(share["file"], "in.vxl");
  EXPECT_EQ(share["title"], "Subject 7");
  EXPECT_TRUE(fs::is_regular_file(out + "/README.txt"));
  EXPECT_EQ(entries_named_part(t.dir), 0);
}

TEST(Share, APackageIsSharedAsItIs) {
  SharedTractogram t;
  const std::string vxlz = t.dir.file("in.vxlz"), out = t.dir.file("shared");
  ASSERT_EQ(test::run_cli("pack " + test::q(t.vxl) + " " + test::q(vxlz)).exit_code, 0);
  const auto r = t.share(vxlz, out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("unpacked by the page"), std::string::npos) << r.output;
  EXPECT_EQ(nlohmann::json::parse(test::slurp(out + "/share.json"))["file"], "in.vxlz");
  EXPECT_EQ(test::slurp(out + "/in.vxlz"), test::slurp(vxlz));
  EXPECT_FALSE(fs::exists(out + "/in.vxl"));
}

TEST(Share, APackageIsUnpackedIntoAVxlThatVerifiesWhenAsked) {
  SharedTractogram t;
  const std::string vxlz = t.dir.file("in.vxlz"), out = t.dir.file("shared");
  ASSERT_EQ(test::run_cli("pack " + test::q(t.vxl) + " " + test::q(vxlz)).exit_code, 0);
  const auto r = t.share(vxlz, out, " --unpack");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("unpacked from the .vxlz"), std::string::npos) << r.output;
  EXPECT_EQ(nlohmann::json::parse(test::slurp(out + "/share.json"))["file"], "in.vxl");
  EXPECT_FALSE(fs::exists(out + "/in.vxlz"));
  const auto verify = test::run_cli("verify " + test::q(out + "/in.vxl"));
  EXPECT_EQ(verify.exit_code, 0) << verify.output;
}

TEST(Share, ADamagedPackageIsRefusedBeforeItIsShared) {
  SharedTractogram t;
  const std::string vxlz = t.dir.file("in.vxlz"), out = t.dir.file("shared");
  ASSERT_EQ(test::run_cli("pack " + test::q(t.vxl) + " " + test::q(vxlz)).exit_code, 0);
  std::vector<char> bytes = test::slurp(vxlz);
  bytes[bytes.size() / 2] ^= 0x40;  // inside the positions: only its section's checksum sees it
  std::ofstream(vxlz, std::ios::binary | std::ios::trunc).write(bytes.data(), std::ssize(bytes));
  const auto r = t.share(vxlz, out);
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("in.vxlz"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("checksum"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(entries_named_part(t.dir), 0);
}

// --level: the folder holds the streamlines of that level of detail as a .vxl (from a package too, unpacked first,
// nothing of the unpacking left), as many as select keeps at that level.
TEST(Share, ALevelOfDetailIsSharedAsAVxlOfItsStreamlines) {
  SharedTractogram t;
  const auto count = test::run_cli("select " + test::q(t.vxl) + " --level 1 --count");
  ASSERT_EQ(count.exit_code, 0) << count.output;
  const std::uint64_t expected = std::stoull(count.output);
  ASSERT_GT(expected, 0u);
  const std::string vxlz = t.dir.file("in.vxlz");
  ASSERT_EQ(test::run_cli("pack " + test::q(t.vxl) + " " + test::q(vxlz)).exit_code, 0);
  for (const std::string& in : {t.vxl, vxlz}) {
    const std::string out = t.dir.file("shared-" + fs::path(in).extension().string().substr(1));
    const auto r = t.share(in, out, " --level 1");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("level 1 of the input"), std::string::npos) << r.output;
    EXPECT_EQ(nlohmann::json::parse(test::slurp(out + "/share.json"))["file"], "in.vxl");
    EXPECT_EQ(VxlFile::open(out + "/in.vxl").meta().streamline_count, expected) << in;
    EXPECT_EQ(test::run_cli("verify " + test::q(out + "/in.vxl")).exit_code, 0);
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(out)) names.push_back(e.path().filename().string());
    EXPECT_EQ(names.size(), std::size(kWebViewerFiles) + 3) << in;  // the .vxl, share.json, README.txt
  }
  const auto beyond = t.share(vxlz, t.dir.file("beyond"), " --level 5");
  EXPECT_EQ(beyond.exit_code, 2) << beyond.output;
  EXPECT_NE(beyond.output.find("in.vxlz has 5 levels of detail"), std::string::npos) << beyond.output;
  EXPECT_FALSE(fs::exists(t.dir.file("beyond")));
  EXPECT_EQ(entries_named_part(t.dir), 0);
}

// A .vxl larger than the page holds is shared as it is: the page draws it from the finest level whose level image
// fits (the folder's README says so); refused, before anything is copied, only where not even the coarsest level's
// fits, naming a selection.
TEST(Share, AVxlLargerThanTheBrowserHoldsIsSharedForTheLevelsThatFit) {
  SharedTractogram t;
  const std::uint64_t size = fs::file_size(t.vxl);
  const VxlFile file = VxlFile::open(t.vxl);
  ShareSettings settings;
  settings.web_viewer_dir = t.viewer;
  const std::string out = t.dir.file("shared");
  for (const std::uint64_t max_bytes : {size, size - 1, size / 20}) {
    settings.max_data_bytes = max_bytes;
    const ShareSummary s = share_folder(t.vxl, out, settings);
    EXPECT_EQ(s.data_bytes, size) << "the file as it is";
    const std::optional<LevelImageSize> image = level_image_size(file, max_bytes);
    ASSERT_TRUE(image.has_value());
    EXPECT_LE(image->bytes, max_bytes);
    const std::string readme = test::slurp<std::string>(out + "/README.txt");
    if (max_bytes == size) {
      EXPECT_FALSE(s.image_level.has_value());
      EXPECT_EQ(readme.find("larger than a browser holds"), std::string::npos);
    } else {
      ASSERT_EQ(s.image_level, image->level);
      EXPECT_NE(readme.find("larger than a browser holds"), std::string::npos) << readme;
      const std::string drawn = image->level == 0 ? "all of it but the streamline tables"
                                                  : "its level of detail " + std::to_string(image->level);
      EXPECT_NE(readme.find(drawn), std::string::npos) << readme;
    }
    if (max_bytes == size - 1) {
      EXPECT_EQ(image->level, 0u) << "level 0 without the streamline tables fits";
    }
    if (max_bytes == size / 20) {
      EXPECT_GE(image->level, 1u) << "level 0 without the streamline tables is not a 20th";
    }
    fs::remove_all(out);
  }
  settings.max_data_bytes = 8;
  const Error e = test::hostile::error_of([&] { share_folder(t.vxl, out, settings); });
  EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
  const std::string why = e.what();
  EXPECT_NE(why.find("in.vxl"), std::string::npos) << why;
  EXPECT_NE(why.find("not even its coarsest level"), std::string::npos) << why;
  EXPECT_NE(why.find("voxlines select"), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(entries_named_part(t.dir), 0);
}

// A package is shared as it is, and the page unpacks it: one whose .vxl the page could not hold is refused before
// anything is copied (its size known from its tables), naming --unpack and the level that fits; with --unpack it is
// shared as a .vxl, which the page draws from the levels that fit.
TEST(Share, APackageWhoseVxlIsLargerThanTheBrowserHoldsIsRefusedBeforeItIsCopied) {
  SharedTractogram t;
  const std::string vxlz = t.dir.file("in.vxlz"), out = t.dir.file("shared");
  ASSERT_EQ(test::run_cli("pack " + test::q(t.vxl) + " " + test::q(vxlz)).exit_code, 0);
  ShareSettings settings;
  settings.web_viewer_dir = t.viewer;
  settings.unpack = true;
  const std::uint64_t unpacked = share_folder(vxlz, t.dir.file("unpacked"), settings).data_bytes;
  const std::uint64_t streamlines = VxlFile::open(t.vxl).meta().streamline_count;
  settings.max_data_bytes = unpacked - 1;
  const ShareSummary as_vxl = share_folder(vxlz, out, settings);
  EXPECT_TRUE(as_vxl.unpacked);
  EXPECT_EQ(as_vxl.image_level, level_image_size(VxlFile::open(out + "/in.vxl"), unpacked - 1)->level);
  fs::remove_all(out);
  settings.unpack = false;
  const Error e = test::hostile::error_of([&] { share_folder(vxlz, out, settings); });
  EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
  const std::string why = e.what();
  EXPECT_NE(why.find("in.vxlz"), std::string::npos) << why;
  EXPECT_NE(why.find("--unpack"), std::string::npos) << why;
  EXPECT_NE(why.find("--level 1 keeps about 1/8 of the streamlines"), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(entries_named_part(t.dir), 0);
  settings.max_data_bytes = unpacked;  // the limit is the unpacked .vxl's size, not the package's
  EXPECT_EQ(share_folder(vxlz, out, settings).streamlines, streamlines);
  fs::remove_all(out);
  // Refused before it is unpacked: a package whose positions unpack refuses (the last chunk's bytes changed behind
  // valid checksums) is refused for its size, not for its positions.
  std::vector<char> bytes = test::slurp(vxlz);
  FileHeader h;
  std::memcpy(&h, bytes.data(), sizeof h);
  for (std::uint32_t i = 0; i < h.section_count; ++i) {
    SectionEntry e;
    std::memcpy(&e, bytes.data() + sizeof h + i * sizeof e, sizeof e);
    if (std::memcmp(e.id, "POSD", 4) == 0) std::memset(bytes.data() + e.offset + e.size - 64, 0xFF, 64);
  }
  test::reseal_checksums(bytes.data(), bytes.size());
  const std::string damaged = t.dir.file("damaged.vxlz");
  std::ofstream(damaged, std::ios::binary).write(bytes.data(), std::ssize(bytes));
  ASSERT_EQ(test::hostile::error_of([&] { unpack_vxlz(damaged, t.dir.file("d.vxl"), UnpackSettings()); }).kind(),
            ErrorKind::Input);
  settings.max_data_bytes = unpacked - 1;
  EXPECT_EQ(test::hostile::error_of([&] { share_folder(damaged, out, settings); }).kind(), ErrorKind::Unsupported);
}

TEST(Share, RefusalsLeaveNoFolder) {
  SharedTractogram t;
  const std::string out = t.dir.file("shared");
  // Not a .vxl: refused as bad input, naming the file.
  auto r = t.share(t.tck, out);
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("in.tck"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // No web viewer: unsupported, saying how it is built.
  r = test::run_cli("share " + test::q(t.vxl) + " " + test::q(out) + " --web-viewer " + test::q(t.dir.file("none")));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("VOXLINES_WEB"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // --unpack given a .vxl, which is unpacked already: a usage error, not ignored.
  r = t.share(t.vxl, out, " --unpack");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--unpack unpacks a .vxlz package"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // Neither a .vxl nor a package: bad input, as without --unpack.
  r = t.share(t.tck, out, " --unpack");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // An existing folder is not touched.
  fs::create_directories(out);
  std::ofstream(out + "/mine.txt") << "keep";
  r = t.share(t.vxl, out);
  EXPECT_EQ(r.exit_code, 5) << r.output;
  EXPECT_EQ(test::slurp(out + "/mine.txt").size(), 4u);
  EXPECT_FALSE(fs::exists(out + "/index.html"));
  EXPECT_EQ(entries_named_part(t.dir), 0);
}

}  // namespace
}  // namespace vxl
