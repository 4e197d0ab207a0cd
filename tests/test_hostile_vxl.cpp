// Hostile .vxl files against `open`, `info` and `export`: names that are not
// UTF-8, section ids that are not ASCII, counts that would size a reservation, provenance of the wrong
// JSON types. Each file is made by the generator in hostile_vxl.h; the outcome must be a clear error
// (exit 3 for a malformed input), never an internal error (exit 70) and never a partial output.
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <tuple>
#include <vector>

#include "converter/export/export_trx.h"
#include "format/base/error.h"
#include "format/base/utf8_check.h"
#include "format/vxl_file.h"
#include "format/vxl_value_sets.h"
#include "tests/hostile_vxl.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;
using test::VxlBytes;

using test::q;

// The error VxlFile::open gives `path` ("no error" when it opens).
std::string open_error(const std::string& path, ErrorKind expected = ErrorKind::Input) {
  try {
    VxlFile::open(path);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), expected) << e.what();
    return e.what();
  }
  return "no error";
}

// One way to damage a valid file, and the words open() must then say.
struct ResealedDamage {
  const char* name;
  std::function<void(VxlBytes&)> damage;
  const char* message;
};

// Each damage applied to `valid` and resealed (so that only the structure can tell): open() refuses it with
// its message, `info` exits 3 and `verify` says invalid.
void expect_refused_on_open(const ScratchDir& dir, const VxlBytes& valid, const std::vector<ResealedDamage>& cases) {
  for (const ResealedDamage& c : cases) {
    SCOPED_TRACE(c.name);
    VxlBytes b = valid;
    c.damage(b);
    b.reseal();
    b.write(dir.file("bad.vxl"));
    EXPECT_NE(open_error(dir.file("bad.vxl")).find(c.message), std::string::npos) << open_error(dir.file("bad.vxl"));
    EXPECT_EQ(test::run_cli("info " + q(dir.file("bad.vxl"))).exit_code, 3);
    const auto v = test::run_cli("verify " + q(dir.file("bad.vxl")));
    EXPECT_EQ(v.exit_code, 1) << v.output;
  }
}

TEST(HostileVxl, TheGeneratedFileIsValidAndHasEveryOptionalSection) {
  ScratchDir dir;
  const VxlBytes b = VxlBytes::make(dir.file("h.vxl"));
  const VxlFile f = VxlFile::open(dir.file("h.vxl"));
  ASSERT_EQ(f.groups().size(), 2u);
  EXPECT_EQ(f.vertex_values().name(0), "fa");
  EXPECT_EQ(f.streamline_values().name(0), "length");
  EXPECT_EQ(b.group_name_bytes().size(), std::string("CST_leftAF right").size());
  EXPECT_EQ(b.value_name_bytes("VVAL").size(), 2u);
  const auto r = test::run_cli("info --json " + q(dir.file("h.vxl")));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"CST_left\""), std::string::npos) << r.output;
}

// One byte of an optional section's id XOR 0x80 made `info --json` die of nlohmann's type_error 316
// (exit 70); ids must be printable ASCII (spec §4), and open says so.
TEST(HostileVxl, SectionIdThatIsNotAsciiIsRefusedOnOpen) {
  ScratchDir dir;
  const VxlBytes valid = VxlBytes::make(dir.file("h.vxl"));
  for (const auto* id : {"PROV", "GRPS", "VVAL", "SVAL"}) {
    for (int k = 0; k < 4; ++k) {
      SCOPED_TRACE(std::string(id) + " byte " + std::to_string(k));
      VxlBytes b = valid;
      b.flip(b.entry_at(id) + k);
      b.reseal();
      b.write(dir.file("bad.vxl"));
      EXPECT_NE(open_error(dir.file("bad.vxl")).find("is not four printable ASCII characters"), std::string::npos);
    }
  }
  VxlBytes b = valid;
  b.flip(b.entry_at("PROV") + 3);
  b.write(dir.file("bad.vxl"));
  const auto r = test::run_cli("info --json " + q(dir.file("bad.vxl")));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("at byte " + std::to_string(valid.entry_at("PROV") + 3) + ": section id"), std::string::npos)
      << r.output;
}

// Rows 2 and 4: a group or value-set name byte XOR 0x80 (never valid UTF-8 after an ASCII byte) made
// `info --json` exit 70 and `export x.trx` exit 5 (libzip refused the member name): open refuses it,
// naming the byte, so both exit 3 and export leaves nothing.
TEST(HostileVxl, NameThatIsNotUtf8IsRefusedOnOpen) {
  ScratchDir dir;
  const VxlBytes valid = VxlBytes::make(dir.file("h.vxl"));
  struct Case {
    std::vector<std::uint64_t> bytes;
    const char* message;
  };
  const Case cases[] = {{valid.group_name_bytes(), "GRPS group name is not valid UTF-8"},
                        {valid.value_name_bytes("VVAL"), "value-set name is not valid UTF-8"},
                        {valid.value_name_bytes("SVAL"), "value-set name is not valid UTF-8"}};
  for (const Case& c : cases)
    for (std::uint64_t at : c.bytes) {
      SCOPED_TRACE("byte " + std::to_string(at));
      VxlBytes b = valid;
      b.flip(at);
      b.reseal();  // even with its checksums right the file is malformed
      b.write(dir.file("bad.vxl"));
      EXPECT_NE(open_error(dir.file("bad.vxl")).find(c.message), std::string::npos);
    }

  VxlBytes b = valid;
  b.flip(valid.group_name_bytes().front());
  b.write(dir.file("bad.vxl"));
  auto r = test::run_cli("info --json " + q(dir.file("bad.vxl")));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("at byte " + std::to_string(valid.group_name_bytes().front())), std::string::npos)
      << r.output;
  r = test::run_cli("export " + q(dir.file("bad.vxl")) + " " + q(dir.file("out.trx")));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out.trx")));

  b = valid;
  b.flip(valid.value_name_bytes("SVAL").back());
  b.write(dir.file("bad.vxl"));
  r = test::run_cli("info --json " + q(dir.file("bad.vxl")));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("value-set name is not valid UTF-8"), std::string::npos) << r.output;
}

// META point_count with its top bit set (byte 15 of META XOR 0x80: 2^63 + P) made `export x.trx`
// reserve 3 * 2^63 floats (exit 70, "vector::reserve"). P + synthetic points <= V is checked on open.
TEST(HostileVxl, PointCountBeyondTheVerticesIsRefusedBeforeAnyReservation) {
  ScratchDir dir;
  const VxlBytes valid = VxlBytes::make(dir.file("h.vxl"));
  const std::uint64_t meta = valid.offset_of("META");
  for (const std::uint64_t at : {meta + 8 + 7, meta + 40 + 7}) {  // point_count, synthetic_point_count
    SCOPED_TRACE("byte " + std::to_string(at));
    VxlBytes b = valid;
    b.flip(at);
    b.write(dir.file("bad.vxl"));
    EXPECT_NE(open_error(dir.file("bad.vxl")).find("exceed vertex_count"), std::string::npos);
    for (const char* out : {"out.trx", "out.tck"}) {
      const auto r = test::run_cli("export " + q(dir.file("bad.vxl")) + " " + q(dir.file(out)));
      EXPECT_EQ(r.exit_code, 3) << out << ": " << r.output;
      EXPECT_NE(r.output.find("at byte " + std::to_string(meta + 8)), std::string::npos) << r.output;
      EXPECT_FALSE(std::filesystem::exists(dir.file(out)));
    }
  }
  // One point more than the vertices is refused too; P = V - synthetic is the largest a file can hold.
  VxlBytes b = valid;
  MetaSection m;
  std::memcpy(&m, b.bytes.data() + meta, sizeof m);
  m.point_count = m.vertex_count - m.synthetic_point_count + 1;
  std::memcpy(b.bytes.data() + meta, &m, sizeof m);
  b.write(dir.file("bad.vxl"));
  EXPECT_NE(open_error(dir.file("bad.vxl")).find("exceed vertex_count"), std::string::npos);
}

// Geometry a resealed file moves (a voxel's tight bounds 1e6 mm away or at 1e38, bounds or origin at
// 1e308, a voxel size or grid that does not cover the bounds) is refused by open() (exit 3), so verify and
// the viewer refuse it too, rather than pass it or draw a blank picture (exit 0).
TEST(HostileVxl, GeometryMovedAwayFromTheLinesIsRefusedOnOpen) {
  ScratchDir dir;
  const VxlBytes valid = VxlBytes::make(dir.file("h.vxl"));
  const std::uint64_t meta = valid.offset_of("META"), voxt = valid.offset_of("VOXT");
  auto put_f32 = [](VxlBytes& b, std::uint64_t at, float v) { std::memcpy(b.bytes.data() + at, &v, 4); };
  auto put_f64 = [](VxlBytes& b, std::uint64_t at, double v) { std::memcpy(b.bytes.data() + at, &v, 8); };
  auto add_f32 = [](VxlBytes& b, std::uint64_t at, float d) {
    float v;
    std::memcpy(&v, b.bytes.data() + at, 4);
    v += d;
    std::memcpy(b.bytes.data() + at, &v, 4);
  };
  expect_refused_on_open(
      dir, valid,
      {
          {"tight bounds moved 1e6 mm",
           [&](VxlBytes& b) {
             add_f32(b, voxt + 16, 1e6f);
             add_f32(b, voxt + 28, 1e6f);
           },
           "voxel 0 tight bounds on x lie outside its cell"},
          {"tight max at 1e38", [&](VxlBytes& b) { put_f32(b, voxt + 64 + 36, 1e38f); },
           "voxel 1 tight bounds on z lie outside its cell"},
          {"bounds max at 1e308", [&](VxlBytes& b) { put_f64(b, meta + 128, 1e308); }, "grid_dims on x is"},
          {"origin at 1e308", [&](VxlBytes& b) { put_f64(b, meta + 64 + 8, 1e308); },
           "grid origin is not at bounds_min"},
          {"voxel size 1e30", [&](VxlBytes& b) { put_f64(b, meta + 56, 1e30); }, "the bounds and voxel size make"},
          {"voxel size 1e-30", [&](VxlBytes& b) { put_f64(b, meta + 56, 1e-30); }, "the bounds and voxel size make"},
          {"grid dims 2^30",
           [&](VxlBytes& b) {
             const std::int32_t d = 1 << 30;
             std::memcpy(b.bytes.data() + meta + 88, &d, 4);
           },
           "grid_dims on x is 1073741824"},
      });
}

// META fields that contradict the sections, and a required section marked optional: open() refuses them (so
// every reader does).
TEST(HostileVxl, MetaFieldsThatContradictTheSectionsAreRefusedOnOpen) {
  ScratchDir dir;
  const VxlBytes valid = VxlBytes::make(dir.file("h.vxl"));
  const std::uint64_t meta = valid.offset_of("META");
  auto put_u32 = [](VxlBytes& b, std::uint64_t at, std::uint32_t v) { std::memcpy(b.bytes.data() + at, &v, 4); };
  expect_refused_on_open(
      dir, valid,
      {
          {"order set 7", [&](VxlBytes& b) { put_u32(b, meta + 100, 7); }, "unknown order set 7 (expected 0, 1 or 2)"},
          {"order set 1 (axis+diag) with K = 3", [&](VxlBytes& b) { put_u32(b, meta + 100, 1); },
           "stored order count 3 for order set 1 (it stores 7)"},
          {"levels not marked required", [&](VxlBytes& b) { put_u32(b, b.entry_at("LODS") + 4, 0); },
           "section LODS must carry the required flag"},
          {"orders not marked required", [&](VxlBytes& b) { put_u32(b, b.entry_at("ORDB") + 4, 0); },
           "section ORDB must carry the required flag"},
      });
}

// The voxel index (VXIX, spec §5.14): list starts that do not rise to the voxline count, or a size for other
// counts, are refused on open (O(voxels)); a section that is both ORDR and ORDB, or neither, too.
TEST(HostileVxl, AVoxelIndexOrOrdersThatDoNotFitTheCountsAreRefusedOnOpen) {
  ScratchDir dir;
  const VxlBytes valid = VxlBytes::make(dir.file("h.vxl"));
  const SectionEntry vxix = valid.entry("VXIX");
  auto put_u64 = [](VxlBytes& b, std::uint64_t at, std::uint64_t v) { std::memcpy(b.bytes.data() + at, &v, 8); };
  expect_refused_on_open(
      dir, valid,
      {
          {"first list start not 0", [&](VxlBytes& b) { put_u64(b, vxix.offset, 1); },
           "VXIX voxel list starts must rise from 0 to the voxline count"},
          {"list starts decreasing", [&](VxlBytes& b) { put_u64(b, vxix.offset + 8, 1ull << 40); },
           "VXIX voxel list starts must rise from 0 to the voxline count"},
          {"size for other counts", [&](VxlBytes& b) { put_u64(b, b.entry_at("VXIX") + 16, vxix.size - 8); },
           "section VXIX size"},
          {"orders under the former id too",
           [&](VxlBytes& b) {
             std::memcpy(b.bytes.data() + b.entry_at("VXIX"), "ORDR", 4);
             const std::uint32_t required = kSectionRequired;
             std::memcpy(b.bytes.data() + b.entry_at("ORDR") + 4, &required, 4);
           },
           "both ORDR and ORDB sections"},
      });
}

// What open() does not read, the users of an entry check: a VXIX entry naming a streamline past the count, or
// more points than the voxel's block holds, is refused by `select` (exit 3), never read past a table; `verify`
// finds every such change, and bits set after an order's last entry.
TEST(HostileVxl, VoxelIndexEntriesAndOrderBitsThatLieAreRefusedWhereUsed) {
  ScratchDir dir;
  const VxlBytes valid = VxlBytes::make(dir.file("h.vxl"));
  const VxlFile f = VxlFile::open(dir.file("h.vxl"));
  const SectionEntry vxix = valid.entry("VXIX");
  const std::uint64_t entries = vxix.offset + 8 * (f.voxels().size() + 1);
  struct Case {
    const char* name;
    std::uint64_t at;
    std::uint32_t value;
    const char* select_message;
    const char* verify_message;
  };
  // The first voxline end of voxel 0's block, cleared: its depth's voxlines no longer fit their part of the block.
  const std::uint64_t vert = valid.entry("VERT").offset + 4 * f.voxels()[0].vertex_first;
  std::uint32_t end_word = 0;
  std::uint64_t end_at = 0;
  for (std::uint32_t i = 0; i < f.voxels()[0].vertex_count && end_at == 0; ++i)
    if (const std::uint32_t w = f.packed_vertices()[f.voxels()[0].vertex_first + i]; w & kPackedVoxlineEnd)
      end_at = vert + 4 * i, end_word = w & ~kPackedVoxlineEnd;
  ASSERT_NE(end_at, 0u);
  const Case cases[] = {
      {"streamline past the count", entries, IndexedVoxline::kStreamlineMask,
       "names a streamline past the streamline count", "differs from the voxline table"},
      {"a voxline end cleared", end_at, end_word, "the voxel's voxlines run past its vertex block",
       "voxline-end bit wrong"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    VxlBytes b = valid;
    std::memcpy(b.bytes.data() + c.at, &c.value, 4);
    b.reseal();
    b.write(dir.file("bad.vxl"));
    const auto r = test::run_cli("select " + q(dir.file("bad.vxl")) + " " + q(dir.file("out.tck")) +
                                 " --include box:-1000,-1000,-1000,1000,1000,1000");
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find(c.select_message), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.tck")));
    const auto v = test::run_cli("verify " + q(dir.file("bad.vxl")));
    EXPECT_EQ(v.exit_code, 1) << v.output;
    EXPECT_NE(v.output.find(c.verify_message), std::string::npos) << v.output;
  }
  // A bit set after the last entry of the first order that does not end on a byte.
  OrderView o;
  for (std::size_t i = 0; i < f.voxels().size() && (o.data == nullptr || o.count * o.bits % 8 == 0); ++i)
    o = f.order(i, 0);
  const std::uint64_t used = std::uint64_t(o.count) * o.bits;
  ASSERT_NE(used % 8, 0u) << "every order ends on a byte";
  VxlBytes b = valid;
  b.bytes[static_cast<std::size_t>(o.data - f.bytes().data()) + used / 8] |= static_cast<char>(0x80);
  b.reseal();
  b.write(dir.file("bits.vxl"));
  const auto v = test::run_cli("verify " + q(dir.file("bits.vxl")));
  EXPECT_EQ(v.exit_code, 1) << v.output;
  EXPECT_NE(v.output.find("has bits set after its last entry"), std::string::npos) << v.output;
}

// The streamline lengths (SLEN, spec §5.15): a size for other counts is refused on open; a length that is not a
// finite number ≥ 0, or longer than all the file's points could make within its bounds, is refused by `select`
// where it is read (exit 3, naming the byte) and by `verify`; another length that is not its points' is found by
// `verify`.
TEST(HostileVxl, StreamlineLengthsThatDoNotFitOrLieAreRefused) {
  ScratchDir dir;
  const VxlBytes valid = VxlBytes::make(dir.file("h.vxl"));
  const SectionEntry slen = valid.entry("SLEN");
  const std::uint64_t streamlines = VxlFile::open(dir.file("h.vxl")).meta().streamline_count;
  ASSERT_EQ(slen.size, 4 * streamlines);
  expect_refused_on_open(dir, valid,
                         {{"size for other counts",
                           [&](VxlBytes& b) {
                             const std::uint64_t smaller = slen.size - 4;
                             std::memcpy(b.bytes.data() + b.entry_at("SLEN") + 16, &smaller, 8);
                           },
                           "section SLEN size"}});
  struct Case {
    const char* name;
    float value;
    bool select_refuses;
    const char* verify_message;
  };
  const Case cases[] = {{"NaN", NAN, true, "is not a finite number"},
                        {"negative", -1.0f, true, "is not a finite number"},
                        {"minus zero", -0.0f, true, "is not a finite number"},
                        {"longer than all the points could make", 1e30f, true, "within its bounds can make"},
                        {"twice as long", 2 * VxlFile::open(dir.file("h.vxl")).streamline_lengths()[streamlines - 1],
                         false, "differs from its points'"}};
  const std::uint64_t last = streamlines - 1;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    VxlBytes b = valid;
    std::memcpy(b.bytes.data() + slen.offset + 4 * last, &c.value, 4);
    b.reseal();
    b.write(dir.file("bad.vxl"));
    const auto r = test::run_cli("select " + q(dir.file("bad.vxl")) + " " + q(dir.file("out.tck")) + " --min-length 1");
    if (c.select_refuses) {
      EXPECT_EQ(r.exit_code, 3) << r.output;
      EXPECT_NE(r.output.find("byte " + std::to_string(slen.offset + 4 * last)), std::string::npos) << r.output;
      EXPECT_FALSE(std::filesystem::exists(dir.file("out.tck")));
    } else {
      EXPECT_EQ(r.exit_code, 0) << r.output;
      std::filesystem::remove(dir.file("out.tck"));
    }
    const auto v = test::run_cli("verify " + q(dir.file("bad.vxl")));
    EXPECT_EQ(v.exit_code, 1) << v.output;
    EXPECT_NE(v.output.find(c.verify_message), std::string::npos) << v.output;
  }
}

// The tables a selection trusts (VOXT, STRM, VXIX or VXLN, SLEN) are checksummed before use: one flipped bit in a
// VXIX entry would add a streamline to the answer, one in SLEN keep a streamline it should not. Each is exit 3
// naming the section, with nothing written.
TEST(HostileVxl, ASelectionRefusesTheTablesItTrustsWhenTheirChecksumsFail) {
  ScratchDir dir;
  const VxlBytes valid = VxlBytes::make(dir.file("h.vxl"));
  const VxlFile f = VxlFile::open(dir.file("h.vxl"));
  const std::uint64_t vxix_entries = valid.entry("VXIX").offset + 8 * (f.voxels().size() + 1);
  for (const auto& [section, at, query] :
       {std::tuple{"VXIX", vxix_entries, std::string(" --include box:-1000,-1000,-1000,1000,1000,1000")},
        std::tuple{"SLEN", valid.entry("SLEN").offset + 1, std::string(" --min-length 1")},
        std::tuple{"STRM", valid.entry("STRM").offset + 8, std::string(" --min-length 1")},
        // A voxel's tight x minimum, its last mantissa bit: within the slack open() allows.
        std::tuple{"VOXT", valid.entry("VOXT").offset + 16, std::string(" --include 0,0,0,5")}}) {
    SCOPED_TRACE(section);
    VxlBytes b = valid;
    b.bytes[static_cast<std::size_t>(at)] ^= 1;  // checksums left stale
    b.write(dir.file("bad.vxl"));
    const auto r = test::run_cli("select " + q(dir.file("bad.vxl")) + " " + q(dir.file("out.tck")) + query);
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find(std::string("checksum mismatch in section ") + section), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.tck")));
  }
}

// PROV is any JSON to open(): fields of the wrong type are ignored, as missing fields are, so neither
// `info` nor `export x.trx` exits 70 on them (type_error 302/306).
TEST(HostileVxl, ProvenanceOfTheWrongTypesIsIgnored) {
  ScratchDir dir;
  const VxlBytes valid = VxlBytes::make(dir.file("h.vxl"));
  const SectionEntry prov = valid.entry("PROV");
  for (const std::string json :
       {R"({"source": 5})", R"({"source": {"name": 5, "format": [1], "bytes": "x"}})",
        R"({"source": {"name": "a", "format": "trx", "bytes": -3, "header": 7}})", R"([1, 2])"}) {
    SCOPED_TRACE(json);
    ASSERT_LE(json.size(), prov.size);
    VxlBytes b = valid;
    std::memset(b.bytes.data() + prov.offset, ' ', prov.size);  // JSON allows the trailing blanks
    std::memcpy(b.bytes.data() + prov.offset, json.data(), json.size());
    b.reseal();
    b.write(dir.file("p.vxl"));
    for (const char* args : {"info --json", "info"}) {
      const auto r = test::run_cli(std::string(args) + " " + q(dir.file("p.vxl")));
      EXPECT_EQ(r.exit_code, 0) << args << ": " << r.output;
    }
    const auto r = test::run_cli("export " + q(dir.file("p.vxl")) + " " + q(dir.file("p.trx")));
    EXPECT_EQ(r.exit_code, 0) << r.output;
  }
}

// The file's own name goes into the JSON as well, and a file system's names need not be UTF-8: `info --json`
// replaces what is not (it died of type_error 316 with exit 70).
TEST(HostileVxl, InfoJsonOfAFileNameThatIsNotUtf8) {
  ScratchDir dir;
  VxlBytes::make(dir.file("h.vxl")).write(dir.file("caf\xe9.vxl"));
  const auto r = test::run_cli("info --json " + q(dir.file("caf\xe9.vxl")));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("caf\xef\xbf\xbd.vxl"), std::string::npos) << r.output;  // U+FFFD
}

// A value-set name from a file name that is not UTF-8 (a TSF called caf\xe9.tsf on a Latin-1 file
// system) is written as UTF-8 (each byte read as Latin-1), so that the converter's own output opens.
TEST(HostileVxl, ValueSetNamesAreWrittenAsUtf8) {
  EXPECT_EQ(value_set_name("caf\xe9"), "caf\xc3\xa9");
  EXPECT_EQ(value_set_name("caf\xc3\xa9"), "caf\xc3\xa9");
  EXPECT_EQ(value_set_name(std::string("a\0b", 3)), "a%00b");  // a stored name ends at its NUL: escaped
  EXPECT_EQ(value_set_name("a/b\\c"), "a%2Fb%5Cc");            // one TRX member file each
  EXPECT_TRUE(is_valid_utf8(value_set_name(std::string(40, 'x') + "\xff\xfe\xfd\xfc\xfb")));
  EXPECT_FALSE(is_valid_utf8("\xc0\xaf"));          // overlong '/'
  EXPECT_FALSE(is_valid_utf8("\xed\xa0\x80"));      // a surrogate
  EXPECT_FALSE(is_valid_utf8("\xf4\x90\x80\x80"));  // above U+10FFFF
  EXPECT_TRUE(is_valid_utf8("\xf4\x8f\xbf\xbf"));

  ScratchDir dir;
  Tractogram t = test::hostile_source();
  t.point_values[0].name = "caf\xe9";
  convert_tractogram(std::move(t), dir.file("v.vxl"), {});
  EXPECT_EQ(VxlFile::open(dir.file("v.vxl")).vertex_values().name(0), "caf\xc3\xa9");
}

// Two groups of one name cannot both be groups/NAME.uint32: export refuses them as unsupported, not only when
// libzip fails to add the second member (exit 5, as if the output were at fault). The input's groups are what
// TRX cannot hold.
TEST(HostileVxl, ExportOfGroupsTrxCannotHoldIsUnsupportedNotAnOutputError) {
  ScratchDir dir;
  for (const std::string& second : {std::string("CST_left"), std::string(70000, 'g')}) {
    Tractogram t = test::hostile_source();
    t.groups[1].name = second;
    convert_tractogram(std::move(t), dir.file("g.vxl"), {});
    try {
      export_trx(VxlFile::open(dir.file("g.vxl")), dir.file("g.trx"));
      ADD_FAILURE() << "exported";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Unsupported) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("g.trx")));
  }
}

}  // namespace
}  // namespace vxl
