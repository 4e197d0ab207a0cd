// Values survive sharing: the value sets of a .vxl travel exactly through a .vxlz package (spec
// vxlz-package-v2.md §4.7: .vxl -> .vxlz -> .vxl gives back VVAL and SVAL byte for byte), and export
// writes them: TRX dpv / dps (with the groups), TCK + TSF for one per-point set. Damaged value sections
// are refused (the damage tests of test_vxlz_package.cpp also run on a package with value sets).
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>

#include "converter/convert/convert.h"
#include "converter/export/export_tck.h"
#include "converter/export/export_trx.h"
#include "converter/package/pack.h"
#include "converter/package/unpack.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/read_tsf.h"
#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_verify.h"
#include "format/vxlz_package.h"
#include "format/vxlz_values.h"
#include "tests/mrtrix_test_files.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;

// Synthetic bundles with a long step (synthetic face points, so interpolated vertex values), a one-point
// and an empty streamline, groups, two per-point sets (one smooth, one of awkward floats) and a
// three-component per-streamline set as a TRX reader gives it.
Tractogram valued_tractogram(std::uint64_t streamlines = 300) {
  SynthSettings settings;
  settings.streamlines = streamlines;
  settings.seed = 11;
  Tractogram t = synthesize_tractogram(settings);
  t.source.path = "valued.trx";
  t.source.format = "trx";
  const float jump[9] = {0, 0, 0, 1, 0.5f, 0.25f, 45, 31, -17};
  t.add_streamline(jump, 3);
  const float one[3] = {-3, 4, 5};
  t.add_streamline(one, 1);
  t.add_streamline(one, 0);
  const std::uint64_t n = t.streamline_count(), p = t.point_count();
  ValueSet smooth{"fa", {}}, odd{"odd values", {}};
  const float awkward[] = {std::numeric_limits<float>::denorm_min(), -0.0f, 1e30f, -7.25f, 0.1f};
  for (std::uint64_t i = 0; i < p; ++i) {
    smooth.values.push_back(0.5f + 0.25f * std::sin(0.01f * float(i)));
    odd.values.push_back(awkward[i % 5] * float(1 + i % 3));
  }
  t.point_values = {smooth, odd};
  for (int c = 0; c < 3; ++c) {
    ValueSet s{"rgb[" + std::to_string(c) + "]", {}};
    for (std::uint64_t j = 0; j < n; ++j) s.values.push_back(float(j) * 0.5f + float(c));
    t.streamline_values.push_back(s);
  }
  t.groups.push_back({"left", {0, 2, 3, n - 3}});
  t.groups.push_back({"right", {1, n - 1}});
  return t;
}

// levels: of the .vxl (a package of a file with levels ships them level by level, which makes it 2.3).
std::string convert_to(Tractogram t, const std::string& path, PositionEncoding positions = PositionEncoding::Packed,
                       std::uint32_t levels = kDefaultLevels) {
  ConvertSettings s;
  s.voxel_size = 10.0;
  s.positions = positions;
  s.levels = levels;
  convert_tractogram(std::move(t), path, s);
  return path;
}

bool same_bytes(std::span<const std::uint8_t> a, std::span<const std::uint8_t> b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size()) == 0);
}

bool same_floats(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), 4 * a.size()) == 0);
}

std::uint16_t minor_version(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  FileHeader h{};
  in.read(reinterpret_cast<char*>(&h), sizeof h);
  return h.version_minor;
}

ErrorKind kind_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.kind();
  }
  return static_cast<ErrorKind>(0);  // no error
}

// Package -----------------------------------------------------------------------------------------

TEST(ValuesPackage, UnpackGivesBackTheValueSetsByteForByte) {
  ScratchDir dir;
  // Without levels the points are shipped in streamline order, with them level by level (package spec §5.1).
  for (std::uint32_t levels : {1u, kDefaultLevels}) {
    const std::string vxl = convert_to(valued_tractogram(), dir.file("v.vxl"), PositionEncoding::Packed, levels);
    const VxlFile original = VxlFile::open(vxl);
    ASSERT_GT(original.meta().synthetic_point_count, 0u) << "the test needs interpolated vertex values";
    ASSERT_EQ(original.vertex_values().size(), 2u);
    ASSERT_EQ(original.streamline_values().size(), 3u);
    for (std::uint32_t bits : {11u, 16u}) {
      SCOPED_TRACE(std::to_string(levels) + " levels, " + std::to_string(bits) + " bits");
      PackSettings settings;
      settings.bits = bits;
      settings.chunk_points = 1000;  // several chunks
      const PackSummary packed = pack_vxl(original, dir.file("v.vxlz"), settings);
      EXPECT_EQ(packed.point_value_sets, 2u);
      EXPECT_EQ(packed.streamline_value_sets, 3u);
      EXPECT_EQ(minor_version(dir.file("v.vxlz")), levels > 1 ? 4 : 1)
          << "a package with value sets is 2.1, shipped level by level (with a checksum per chunk) 2.4";
      UnpackSettings unpacking;
      unpacking.levels = levels;
      const UnpackSummary back = unpack_vxlz(dir.file("v.vxlz"), dir.file("u.vxl"), unpacking);
      EXPECT_EQ(unpacked_vxl_bytes(VxlzFile::open(dir.file("v.vxlz")), unpacking),
                std::filesystem::file_size(dir.file("u.vxl")))
          << "the value sets' sizes, known from their sections' heads";
      if (levels > 1) {  // a level alone comes without its value sets
        UnpackSettings look;
        look.level = 1;
        unpack_vxlz(dir.file("v.vxlz"), dir.file("look.vxl"), look);
        EXPECT_EQ(unpacked_vxl_bytes(VxlzFile::open(dir.file("v.vxlz")), look),
                  std::filesystem::file_size(dir.file("look.vxl")));
        std::filesystem::remove(dir.file("look.vxl"));
      }
      EXPECT_EQ(back.point_value_sets, 2u);
      EXPECT_EQ(back.streamline_value_sets, 3u);
      const VerifyResult verified = verify_vxl(dir.file("u.vxl"));
      EXPECT_TRUE(verified.valid) << verified.problem;
      const VxlFile copy = VxlFile::open(dir.file("u.vxl"));
      EXPECT_TRUE(same_bytes(original.vertex_values().payload(), copy.vertex_values().payload()))
          << "VVAL (names, min/max, every vertex value, padding) must come back exactly";
      EXPECT_TRUE(same_bytes(original.streamline_values().payload(), copy.streamline_values().payload()));
    }
  }
}

TEST(ValuesPackage, SectionsAreOptionalAndAPackageWithoutValuesStays20) {
  ScratchDir dir;
  const VxlFile f = VxlFile::open(convert_to(valued_tractogram(50), dir.file("v.vxl")));
  pack_vxl(f, dir.file("v.vxlz"), {});
  const VxlzFile z = VxlzFile::open(dir.file("v.vxlz"));
  ASSERT_TRUE(z.has_section(section_id("PVAL")) && z.has_section(section_id("SVAL")));
  // Optional: a 2.0 reader skips them (spec §2.2) and still unpacks every streamline.
  std::ifstream in(dir.file("v.vxlz"), std::ios::binary);
  FileHeader h{};
  in.read(reinterpret_cast<char*>(&h), sizeof h);
  for (std::uint32_t i = 0; i < h.section_count; ++i) {
    SectionEntry e{};
    in.read(reinterpret_cast<char*>(&e), sizeof e);
    const std::string id(e.id, 4);
    if (id == "PVAL" || id == "SVAL") {
      EXPECT_EQ(e.flags & kSectionRequired, 0u) << id;
    }
  }

  Tractogram plain = valued_tractogram(50);
  plain.point_values.clear();
  plain.streamline_values.clear();
  pack_vxl(VxlFile::open(convert_to(Tractogram(plain), dir.file("p.vxl"), PositionEncoding::Packed, 1)),
           dir.file("p.vxlz"), {});
  EXPECT_EQ(minor_version(dir.file("p.vxlz")), 0) << "writers write the lowest version that holds what they write";
  pack_vxl(VxlFile::open(convert_to(Tractogram(plain), dir.file("l.vxl"))), dir.file("l.vxlz"), {});
  EXPECT_EQ(minor_version(dir.file("l.vxlz")), 4)
      << "a file with levels is shipped level by level, with a checksum per chunk";
  EXPECT_FALSE(VxlzFile::open(dir.file("p.vxlz")).has_section(section_id("PVAL")));
  unpack_vxlz(dir.file("p.vxlz"), dir.file("p2.vxl"), {});
  EXPECT_TRUE(VxlFile::open(dir.file("p2.vxl")).vertex_values().empty());
}

TEST(ValuesPackage, ValueSectionCodecIsExactForEitherCoding) {
  // A smooth set (the XOR planes win) and one that repeats a few arbitrary bit patterns in runs, as
  // per-fixel values do (plain wins: deflate matches whole values): both codings are exercised.
  std::vector<NamedValues> sets(2);
  sets[0].name = "steady";
  sets[1].name = "palette";
  std::uint32_t x = 12345;
  float palette[8];
  for (float& p : palette) {
    x = x * 1664525u + 1013904223u;
    std::memcpy(&p, &x, 4);  // any bit pattern, NaNs included
  }
  for (int i = 0; i < 5000; ++i) {
    sets[0].values.push_back(1.0f + float(i) * 1e-4f);
    if (i % 4 == 0) x = x * 1664525u + 1013904223u;
    sets[1].values.push_back(palette[x >> 29]);
  }
  const std::vector<std::uint8_t> payload = encode_value_section(sets);
  std::uint32_t codings[2];
  std::memcpy(&codings[0], payload.data() + 16 + 48, 4);
  std::memcpy(&codings[1], payload.data() + 16 + 64 + 48, 4);
  EXPECT_EQ(codings[0], kValueCodingXorPlanes);
  EXPECT_EQ(codings[1], kValueCodingPlain);
  const auto back = decode_value_section(payload, 5000, {"x.vxlz", "PVAL", 0});
  ASSERT_EQ(back.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(back[k].name, sets[k].name);
    EXPECT_TRUE(same_floats(back[k].values, sets[k].values)) << k;
  }
}

TEST(ValuesPackage, DamagedValueSectionsAreRefusedBeforeAllocating) {
  std::vector<NamedValues> sets(1);
  sets[0] = {"v", std::vector<float>(100, 2.5f)};
  const std::vector<std::uint8_t> good = encode_value_section(sets);
  const StreamContext at{"x.vxlz", "PVAL", 1000};
  auto refused = [&](std::vector<std::uint8_t> b, std::uint64_t count = 100) {
    return kind_of([&] { decode_value_section(b, count, at); });
  };
  EXPECT_EQ(refused(good, 101), ErrorKind::Input) << "value count other than PACK's / META's";
  auto patched = [&](std::size_t offset, std::uint64_t value, int width) {
    std::vector<std::uint8_t> b = good;
    std::memcpy(b.data() + offset, &value, width);
    return b;
  };
  EXPECT_EQ(refused(patched(0, 0, 4)), ErrorKind::Input) << "no sets";
  EXPECT_EQ(refused(patched(0, 65, 4)), ErrorKind::Input) << "65 sets";
  EXPECT_EQ(refused(patched(4, 1, 4)), ErrorKind::Input) << "reserved";
  EXPECT_EQ(refused(patched(16 + 47, 'x', 1)), ErrorKind::Input) << "name without NUL";
  EXPECT_EQ(refused(patched(16 + 20, 'x', 1)), ErrorKind::Input) << "name padding not zero";
  EXPECT_EQ(refused(patched(16 + 48, 7, 4)), ErrorKind::Unsupported) << "unknown coding";
  EXPECT_EQ(refused(patched(16 + 52, 1, 4)), ErrorKind::Input) << "entry reserved";
  EXPECT_EQ(refused(patched(16 + 56, ~0ull, 8)), ErrorKind::Input) << "stream past the end";
  EXPECT_EQ(refused(patched(80, 1ull << 40, 8)), ErrorKind::Input) << "raw size other than 4 x count, before inflating";
  std::vector<std::uint8_t> longer = good;
  longer.push_back(0);
  EXPECT_EQ(refused(longer), ErrorKind::Input) << "bytes after the last stream";
  for (std::size_t n = 0; n < good.size(); ++n)
    EXPECT_EQ(refused({good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n)}), ErrorKind::Input)
        << "truncated to " << n;
}

TEST(ValuesPackage, ConnectingValuesThatDifferFromTheNextPointAreRefused) {
  // The package ships no connecting-vertex values: a .vxl whose connecting value is not the next
  // voxline's first could not come back exactly, so pack refuses it rather than change it.
  ScratchDir dir;
  const std::string vxl = convert_to(valued_tractogram(50), dir.file("v.vxl"));
  const VxlFile f = VxlFile::open(vxl);
  // Find a connecting vertex: the last vertex of a voxline followed by one of the same streamline.
  std::uint64_t connecting = ~0ull;
  auto strm = f.streamline_first_voxline();
  std::vector<std::uint64_t> cursor;
  for (const VoxelEntry& v : f.voxels()) cursor.push_back(v.vertex_first);
  for (std::uint64_t s = 0; s + 1 < strm.size() && connecting == ~0ull; ++s)
    for (std::uint64_t j = strm[s]; j < strm[s + 1]; ++j) {
      const VoxlineEntry& e = f.voxlines()[j];
      const std::uint64_t own = e.count_flags & kVoxlineCountMask;
      if (j + 1 < strm[s + 1]) {
        connecting = cursor[e.voxel] + own;
        break;
      }
      cursor[e.voxel] += own;
    }
  ASSERT_NE(connecting, ~0ull);
  const std::uint64_t at = f.find_section(section_id("VVAL"))->offset + value_sets_data_offset(2) + 4 * connecting;
  std::vector<char> bytes = test::slurp(vxl);
  bytes[at] ^= 1;
  std::ofstream(dir.file("bad.vxl"), std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  // No checksum to reseal: VxlFile::open checks the structure only, and pack reads the values.
  const VxlFile bad = VxlFile::open(dir.file("bad.vxl"));
  try {
    pack_vxl(bad, dir.file("bad.vxlz"), {});
    ADD_FAILURE() << "packed";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("connecting vertex's value"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.vxlz")));
}

// Export ------------------------------------------------------------------------------------------

TEST(ValuesExport, TrxCarriesDpvDpsAndGroupsExactly) {
  ScratchDir dir;
  const Tractogram source = valued_tractogram();
  const VxlFile f = VxlFile::open(convert_to(valued_tractogram(), dir.file("v.vxl")));
  export_trx(f, dir.file("back.trx"));
  const Tractogram back = read_tractogram(dir.file("back.trx"));
  EXPECT_EQ(back.offsets, source.offsets);
  ASSERT_EQ(back.point_values.size(), source.point_values.size());
  for (std::size_t k = 0; k < source.point_values.size(); ++k) {
    EXPECT_EQ(back.point_values[k].name, source.point_values[k].name);
    EXPECT_TRUE(same_floats(back.point_values[k].values, source.point_values[k].values))
        << source.point_values[k].name << ": the source points' values, synthetic and connecting vertices dropped";
  }
  ASSERT_EQ(back.streamline_values.size(), 3u) << "rgb[0..2] go out as one dps/rgb.3.float32 and come back as three";
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(back.streamline_values[k].name, source.streamline_values[k].name);
    EXPECT_TRUE(same_floats(back.streamline_values[k].values, source.streamline_values[k].values)) << k;
  }
  ASSERT_EQ(back.groups.size(), 2u);
  EXPECT_EQ(back.groups[0].members, source.groups[0].members);
  EXPECT_EQ(back.groups[1].name, "right");

  // And through a package: .vxl -> .vxlz -> .vxl -> .trx gives the same values.
  pack_vxl(f, dir.file("v.vxlz"), {});
  unpack_vxlz(dir.file("v.vxlz"), dir.file("u.vxl"), {});
  export_trx(VxlFile::open(dir.file("u.vxl")), dir.file("u.trx"));
  const Tractogram again = read_tractogram(dir.file("u.trx"));
  ASSERT_EQ(again.point_values.size(), 2u);
  EXPECT_TRUE(same_floats(again.point_values[1].values, source.point_values[1].values));
}

// A name no TRX member can carry ("a/b") is mapped when converting (to "a%2Fb", as VTK escapes it), so that
// export never meets it: the set goes to the TRX under the mapped name.
TEST(ValuesExport, UnusableSetNamesAreMappedAtConversionAndExported) {
  ScratchDir dir;
  Tractogram t = valued_tractogram(20);
  t.point_values[0].name = "a/b";
  const VxlFile f = VxlFile::open(convert_to(std::move(t), dir.file("v.vxl")));
  ASSERT_EQ(f.vertex_values().name(0), "a%2Fb");
  export_trx(f, dir.file("x.trx"));
  const Tractogram back = read_tractogram(dir.file("x.trx"));
  ASSERT_FALSE(back.point_values.empty());
  EXPECT_EQ(back.point_values[0].name, "a%2Fb");
}

// A TCK and its TSF, read as the converter reads them.
Tractogram tck_with_tsf(const ScratchDir& dir) {
  using test::raw;
  const float nan = NAN, inf = INFINITY;
  test::write_mrtrix_file(
      dir.file("t.tck"), "mrtrix tracks", "Float32LE",
      raw<float>({0,   0,   0,   1,   0.5f, 0.25f, 45, 31,   -17,   nan,    nan, nan, -3,  4,   5,   nan, nan,
                  nan, nan, nan, nan, 2,    2,     2,  2.5f, 2.25f, 2.125f, nan, nan, nan, inf, inf, inf}),
      "timestamp: 1234.5\n");
  test::write_mrtrix_file(dir.file("afd.tsf"), "mrtrix track scalars", "Float32LE",
                          raw<float>({0.1f, 0.2f, 0.7f, nan, 1e-40f, nan, nan, -2, 3.5f, nan, inf}),
                          "timestamp: 1234.5\n");
  Tractogram t = read_tractogram(dir.file("t.tck"));
  attach_tsf(t, dir.file("afd.tsf"));
  return t;
}

TEST(ValuesExport, TckAndTsfReadBackBitExact) {
  ScratchDir dir;
  const Tractogram source = tck_with_tsf(dir);
  // float32 positions: the points too come back bit for bit.
  const VxlFile f = VxlFile::open(convert_to(tck_with_tsf(dir), dir.file("v.vxl"), PositionEncoding::Float32));
  ASSERT_GT(f.meta().synthetic_point_count, 0u);
  TckExportSettings settings;
  settings.tsf_path = dir.file("out.tsf");
  const ExportSummary s = export_tck(f, dir.file("out.tck"), settings);
  EXPECT_EQ(s.value_set, "afd");
  EXPECT_TRUE(s.warnings.empty()) << s.warnings[0];
  Tractogram back = read_tractogram(dir.file("out.tck"));
  EXPECT_EQ(back.offsets, source.offsets);
  EXPECT_TRUE(same_floats(back.positions, source.positions));
  attach_tsf(back, dir.file("out.tsf"));  // also checks the point counts
  EXPECT_TRUE(back.source.warnings.empty()) << "same timestamp in TCK and TSF: " << back.source.warnings[0];
  ASSERT_EQ(back.point_values.size(), 1u);
  EXPECT_TRUE(same_floats(back.point_values[0].values, source.point_values[0].values));
  const TrackScalars raw = read_tsf(dir.file("out.tsf"));
  EXPECT_EQ(raw.offsets, source.offsets);
  EXPECT_TRUE(raw.warnings.empty());

  // Without a TSF the library says what was left out (the CLI prints it).
  const ExportSummary plain = export_tck(f, dir.file("plain.tck"));
  ASSERT_EQ(plain.warnings.size(), 1u);
  EXPECT_NE(plain.warnings[0].find("per-point"), std::string::npos);
}

TEST(ValuesExport, TsfChoosesTheSetAndRefusesWhatItCannotWrite) {
  ScratchDir dir;
  const VxlFile f = VxlFile::open(convert_to(valued_tractogram(40), dir.file("v.vxl")));
  TckExportSettings settings;
  settings.tsf_path = dir.file("o.tsf");
  settings.value = "odd values";
  const ExportSummary s = export_tck(f, dir.file("o.tck"), settings);
  EXPECT_EQ(s.value_set, "odd values");
  EXPECT_EQ(s.warnings.size(), 3u) << "one other per-point set, the per-streamline sets and the groups are not written";
  Tractogram back = read_tractogram(dir.file("o.tck"));
  attach_tsf(back, dir.file("o.tsf"));
  EXPECT_TRUE(same_floats(back.point_values[0].values, valued_tractogram(40).point_values[1].values));

  settings.value = "nope";
  settings.tsf_path = dir.file("n.tsf");
  EXPECT_EQ(kind_of([&] { export_tck(f, dir.file("n.tck"), settings); }), ErrorKind::Usage);
  Tractogram none = valued_tractogram(40);
  none.point_values.clear();
  const VxlFile g = VxlFile::open(convert_to(std::move(none), dir.file("none.vxl")));
  settings.value.reset();
  EXPECT_EQ(kind_of([&] { export_tck(g, dir.file("n.tck"), settings); }), ErrorKind::Usage);
  Tractogram nan = valued_tractogram(40);
  nan.point_values[0].values[17] = NAN;
  const VxlFile h = VxlFile::open(convert_to(std::move(nan), dir.file("nan.vxl")));
  EXPECT_EQ(kind_of([&] { export_tck(h, dir.file("n.tck"), settings); }), ErrorKind::Unsupported);
  for (const char* name : {"n.tck", "n.tsf"}) EXPECT_FALSE(std::filesystem::exists(dir.file(name))) << name;
}

TEST(ValuesCli, PackAndExportNoLongerWarnAndTsfGoesWithTck) {
  ScratchDir dir;
  const std::string vxl = convert_to(valued_tractogram(40), dir.file("v.vxl"));
  auto r = test::run_cli("pack '" + vxl + "' '" + dir.file("v.vxlz") + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("values: 2 per-point and 3 per-streamline set(s), exact"), std::string::npos) << r.output;
  r = test::run_cli("export '" + vxl + "' '" + dir.file("v.trx") + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
  r = test::run_cli("export '" + vxl + "' '" + dir.file("v.tck") + "' --tsf '" + dir.file("v.tsf") + "' --value fa");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("v.tsf")));
  r = test::run_cli("export '" + vxl + "' '" + dir.file("w.trx") + "' --tsf '" + dir.file("w.tsf") + "'");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = test::run_cli("export '" + vxl + "' '" + dir.file("w.tck") + "' --tsf '" + dir.file("w.tsf") +
                    "' --value missing");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("w.tck")));
}

TEST(ValuesReal, AfdTsfSurvivesPackAndExport) {
  VXL_REQUIRE_REAL_DATA();
  ScratchDir dir;
  Tractogram t = read_tractogram(test::real("test_data__tracks.tck"));
  attach_tsf(t, test::real("test_data__afd.tsf"));
  const std::vector<float> afd = t.point_values[0].values;
  const VxlFile f = VxlFile::open(convert_to(std::move(t), dir.file("tracks.vxl")));
  pack_vxl(f, dir.file("tracks.vxlz"), {});
  unpack_vxlz(dir.file("tracks.vxlz"), dir.file("u.vxl"), {});
  const VxlFile u = VxlFile::open(dir.file("u.vxl"));
  EXPECT_TRUE(same_bytes(f.vertex_values().payload(), u.vertex_values().payload()));
  TckExportSettings settings;
  settings.tsf_path = dir.file("afd.tsf");
  export_tck(u, dir.file("tracks.tck"), settings);
  EXPECT_TRUE(same_floats(read_tsf(dir.file("afd.tsf")).values, afd));
}

}  // namespace
}  // namespace vxl
