// Every JSON the converter reads (a TRX header.json, the PROV of a .vxl or .vxlz) is refused when it nests
// deeper than kMaxJsonDepth, before it is parsed: deeper documents would exhaust the stack. The view
// file's parse has its own test beside the other view-file tests.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "converter/readers/read_tractogram.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "tests/hostile_inputs.h"
#include "tests/hostile_vxl.h"
#include "tests/test_support.h"

namespace {

namespace hostile = vxl::test::hostile;
using vxl::test::q;
using vxl::test::ScratchDir;

using vxl::test::contains;

const std::string kTooDeep = "JSON nested deeper than " + std::to_string(vxl::kMaxJsonDepth) + " arrays and objects";

TEST(JsonLimits, DepthCountsBracketsOutsideStringsOnly) {
  using vxl::json_too_deep_at;
  EXPECT_FALSE(json_too_deep_at("[[1]]", 2));
  EXPECT_EQ(json_too_deep_at("[[1]]", 1), std::optional<std::uint64_t>(1));
  EXPECT_EQ(json_too_deep_at(R"({"a": [{"b": 1}]})", 2), std::optional<std::uint64_t>(7));
  EXPECT_FALSE(json_too_deep_at(R"(["[[[[", "\"[[[["])", 1));  // in strings, escaped quotes included
  EXPECT_FALSE(json_too_deep_at("[1] [2] [3]", 1));            // siblings do not add up
  EXPECT_FALSE(json_too_deep_at(hostile::nested_json(vxl::kMaxJsonDepth)));
  EXPECT_EQ(json_too_deep_at(hostile::nested_json(vxl::kMaxJsonDepth + 1)),
            std::optional<std::uint64_t>(vxl::kMaxJsonDepth));

  EXPECT_TRUE(vxl::parse_json("[1, 2", "f.json", 0, "x").is_discarded());  // malformed: as before
  EXPECT_EQ(vxl::parse_json(hostile::nested_json(3), "f.json", 0, "x").dump(), "[[[]]]");
  try {
    (void)vxl::parse_json(" " + hostile::nested_json(100000), "f.json", 40, "view file");
    ADD_FAILURE() << "no error";
  } catch (const vxl::Error& e) {
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Input);
    EXPECT_EQ(std::string(e.what()),
              "f.json: at byte " + std::to_string(40 + 1 + vxl::kMaxJsonDepth) + ": view file: " + kTooDeep);
  }
}

TEST(JsonLimits, DeepTrxHeaderIsMalformed) {
  ScratchDir dir;
  for (const std::size_t depth : {std::size_t{vxl::kMaxSourceJsonDepth}, std::size_t{60000}}) {
    SCOPED_TRACE(depth);
    const std::string p = dir.file("deep.trx"), out = dir.file("deep.vxl");
    hostile::trx_deep_header(p, depth);
    try {
      (void)vxl::read_tractogram(p);
      ADD_FAILURE() << "no error";
    } catch (const vxl::Error& e) {
      EXPECT_EQ(e.kind(), vxl::ErrorKind::Input) << e.what();
      EXPECT_TRUE(
          contains(e.what(), "header.json: JSON nested deeper than " + std::to_string(vxl::kMaxSourceJsonDepth)))
          << e.what();
    }
    const auto r = vxl::test::run_cli("convert " + q(p) + " " + q(out));
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
  // The deepest header a source may have converts, and its PROV is within the limit everywhere.
  const std::string p = dir.file("ok.trx"), out = dir.file("ok.vxl");
  hostile::trx_deep_header(p, vxl::kMaxSourceJsonDepth - 1);
  const auto c = vxl::test::run_cli("convert " + q(p) + " " + q(out));
  ASSERT_EQ(c.exit_code, 0) << c.output;
  for (const std::string& cmd :
       {"verify " + q(out), "info --json " + q(out), "export " + q(out) + " " + q(dir.file("ok2.trx"))}) {
    const auto r = vxl::test::run_cli(cmd);
    EXPECT_EQ(r.exit_code, 0) << cmd << ": " << r.output;
  }
}

// A PROV nested 100000 deep (about 200 KB), deep enough to overflow the stack, is refused by info, export,
// unpack and verify alike.
TEST(JsonLimits, DeepProvenanceIsRefusedByEveryCommand) {
  ScratchDir dir;
  const std::string p = dir.file("deep.vxl");
  vxl::test::vxl_with_deep_provenance(p, 100000).write(p);
  for (const std::string& args : {"info " + q(p), "info --json " + q(p), "export " + q(p) + " " + q(dir.file("o.trx")),
                                  "export " + q(p) + " " + q(dir.file("o.tck")) + " --tsf " + q(dir.file("o.tsf")),
                                  "pack " + q(p) + " " + q(dir.file("o.vxlz")),
                                  "select " + q(p) + " " + q(dir.file("o.vxl")) + " --include 0,0,0,1000",
                                  "select " + q(p) + " --count --min-length 1"}) {
    SCOPED_TRACE(args);
    const auto r = vxl::test::run_cli(args);
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_TRUE(contains(r.output, "deep.vxl: at byte ")) << r.output;
    EXPECT_TRUE(contains(r.output, "PROV: " + kTooDeep)) << r.output;
  }
  for (const char* out : {"o.trx", "o.tck", "o.tsf", "o.vxlz", "o.vxl"})
    EXPECT_FALSE(std::filesystem::exists(dir.file(out))) << out;
  const auto v = vxl::test::run_cli("verify " + q(p));
  EXPECT_EQ(v.exit_code, 1) << v.output;
  EXPECT_TRUE(contains(v.output, kTooDeep)) << v.output;

  // Just within the limit: every command reads it.
  const std::string ok = dir.file("ok.vxl");
  vxl::test::vxl_with_deep_provenance(ok, vxl::kMaxJsonDepth - 3).write(ok);
  for (const std::string& args :
       {"verify " + q(ok), "info --json " + q(ok), "export " + q(ok) + " " + q(dir.file("k.trx"))}) {
    const auto r = vxl::test::run_cli(args);
    EXPECT_EQ(r.exit_code, 0) << args << ": " << r.output;
  }
}

}  // namespace
