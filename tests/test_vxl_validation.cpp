// VxlFile::open's structure checks (spec §7, steps 1-4), one damaged file per refusal. Each damage is
// made behind valid checksums (resealed), so only the structure check itself can catch it, and each case
// names the message it expects: a validator that refused everything, or nothing, fails here.
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "converter/convert/convert.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "tests/reseal_checksums.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;
using test::slurp;

// Streamlines crossing several 5 mm voxels.
Tractogram crossing_tractogram() {
  Tractogram t;
  t.source.path = "crossing.tck";
  for (int s = 0; s < 6; ++s) {
    std::vector<float> pts;
    for (int i = 0; i < 12; ++i) pts.insert(pts.end(), {2.0f * i, 1.5f * s + 0.2f * i, 0.7f * s});
    t.add_streamline(pts.data(), 12);
  }
  return t;
}

// A valid file's bytes, with typed access to the header, the section table, META and the voxel table.
struct FileBytes {
  std::vector<char> b;

  template <typename T>
  T get(std::uint64_t at) const {
    T v;
    std::memcpy(&v, b.data() + at, sizeof v);
    return v;
  }
  template <typename T>
  void set(std::uint64_t at, T v) {
    std::memcpy(b.data() + at, &v, sizeof v);
  }
  std::uint32_t section_count() const { return get<std::uint32_t>(32); }
  std::uint64_t entry_at(const char* id) const {  // the section table entry of `id`
    for (std::uint32_t i = 0; i < section_count(); ++i)
      if (std::memcmp(b.data() + 64 + 32 * i, id, 4) == 0) return 64 + 32 * i;
    throw std::logic_error(std::string("no section ") + id);
  }
  std::uint64_t section_at(const char* id) const { return get<std::uint64_t>(entry_at(id) + 8); }
  std::uint64_t meta() const { return section_at("META"); }
  std::uint64_t voxel(std::uint32_t i) const { return section_at("VOXT") + 64ull * i; }
  std::uint32_t voxel_count() const { return get<std::uint32_t>(meta() + 48); }
};

struct Case {
  const char* name;
  std::function<void(FileBytes&)> damage;
  const char* expected;  // a part of the message
  ErrorKind kind = ErrorKind::Input;
};

// Fields by their spec offsets: header (§3), section entry (§4: id 0, flags 4, offset 8, size 16), META
// (§5.1), voxel entry (§5.3: flags 12, vertex_first 40, vertex_count 48, segment_count 52, order_offset 56).
using u32 = std::uint32_t;
using u64 = std::uint64_t;

// The header's magic and version, and packed positions (spec §3, §5.4).
std::vector<Case> position_cases() {
  return {
      {"short", [](FileBytes& f) { f.b.resize(40); }, "file too short for a .vxl header"},
      {"magic", [](FileBytes& f) { f.b[0] ^= 0x20; }, "bad magic"},
      {"major", [](FileBytes& f) { f.set<std::uint16_t>(8, 3); }, "major version 3", ErrorKind::Unsupported},
      // Packed positions (the default the base file was converted with).
      {"position_encoding", [](FileBytes& f) { f.set<u32>(f.meta() + 152, 2); }, "unknown position encoding 2"},
      {"packed_in_version_1", [](FileBytes& f) { f.set<std::uint16_t>(8, 1); }, "packed positions in a version 1 file"},
      {"tight_bounds_nan", [](FileBytes& f) { f.set<float>(f.voxel(1) + 20, std::nanf("")); },
       "voxel 1 tight bounds are not finite and ordered"},
      {"tight_bounds_reversed",
       [](FileBytes& f) {
         f.set<float>(f.voxel(0) + 16, f.get<float>(f.voxel(0) + 28) + 1.0f);  // min x past max x
       },
       "voxel 0 tight bounds are not finite and ordered"},
      {"tight_bounds_overflow",
       [](FileBytes& f) {
         f.set<float>(f.voxel(0) + 24, -3e38f);  // max - min overflows binary32
         f.set<float>(f.voxel(0) + 36, 3e38f);
       },
       "voxel 0 tight bounds are not finite and ordered"},
  };
}

// The header and the section table (spec §3, §4).
std::vector<Case> header_and_table_cases() {
  return {
      {"header_size", [](FileBytes& f) { f.set<u32>(12, 72); }, "header_size must be 64"},
      {"file_size", [](FileBytes& f) { f.set<u64>(16, f.b.size() + 64); }, "truncated or extended file"},
      {"table_offset", [](FileBytes& f) { f.set<u64>(24, 128); }, "section table must start at byte 64"},
      {"no_sections", [](FileBytes& f) { f.set<u32>(32, 0); }, "section count must be 1..64"},
      {"too_many_sections", [](FileBytes& f) { f.set<u32>(32, 65); }, "section count must be 1..64"},
      {"header_flags", [](FileBytes& f) { f.set<u32>(36, 1); }, "unknown header flags"},
      {"table_past_end",
       [](FileBytes& f) {
         f.b.resize(128);
         f.set<u64>(16, 128);
       },
       "section table runs past the end of the file"},
      {"unaligned", [](FileBytes& f) { f.set<u64>(f.entry_at("DIRS") + 8, f.section_at("DIRS") + 8); },
       "offset is not a multiple of 64"},
      {"overlap", [](FileBytes& f) { f.set<u64>(f.entry_at("DIRS") + 8, f.section_at("META")); },
       "overlaps the table or the previous section"},
      {"past_end", [](FileBytes& f) { f.set<u64>(f.entry_at("PROV") + 16, f.b.size()); },
       "runs past the end of the file"},
      {"section_flags", [](FileBytes& f) { f.set<u32>(f.entry_at("DIRS") + 4, 3); }, "has unknown flags"},
      {"twice", [](FileBytes& f) { std::memcpy(f.b.data() + f.entry_at("DIRS"), "META", 4); },
       "section META appears twice"},
      {"unknown_required", [](FileBytes& f) { std::memcpy(f.b.data() + f.entry_at("DIRS"), "ZZZZ", 4); },
       "required section ZZZZ is unknown to this reader", ErrorKind::Unsupported},
      {"missing",
       [](FileBytes& f) {
         const u64 at = f.entry_at("DIRS");
         std::memcpy(f.b.data() + at, "ZZZZ", 4);
         f.set<u32>(at + 4, 0);  // an optional unknown section: skipped, so DIRS is missing
       },
       "required section DIRS is missing"},
  };
}

// META and the sizes it implies (spec §5.1).
std::vector<Case> meta_cases() {
  auto meta_u64 = [](int at, u64 v) { return [=](FileBytes& f) { f.set<u64>(f.meta() + at, v); }; };
  auto meta_add = [](int at, u64 d) {
    return [=](FileBytes& f) { f.set<u64>(f.meta() + at, f.get<u64>(f.meta() + at) + d); };
  };
  return {
      {"meta_size", [](FileBytes& f) { f.set<u64>(f.entry_at("META") + 16, 192); }, "META must be 256 bytes"},
      {"voxel_size_zero", [](FileBytes& f) { f.set<double>(f.meta() + 56, 0.0); },
       "voxel size must be finite and positive"},
      {"voxel_size_nan", [](FileBytes& f) { f.set<double>(f.meta() + 56, std::nan("")); },
       "voxel size must be finite and positive"},
      {"no_orders", [](FileBytes& f) { f.set<u32>(f.meta() + 52, 0); }, "stored order count must be 1..64"},
      {"many_orders", [](FileBytes& f) { f.set<u32>(f.meta() + 52, 65); }, "stored order count must be 1..64"},
      {"voxel_count", [](FileBytes& f) { f.set<u32>(f.meta() + 48, 0x80000000u); }, "voxel count exceeds 2^31-1"},
      {"grid_dims", [](FileBytes& f) { f.set<std::int32_t>(f.meta() + 92, -1); }, "negative grid dimension"},
      {"grid_origin", [](FileBytes& f) { f.set<double>(f.meta() + 64, INFINITY); }, "non-finite grid origin or bounds"},
      {"bounds", [](FileBytes& f) { f.set<double>(f.meta() + 128, std::nan("")); }, "non-finite grid origin or bounds"},
      {"dirs_size", [](FileBytes& f) { f.set<u32>(f.meta() + 52, 4); },
       "section DIRS size 48 does not match stored_order_count"},
      {"voxt_size", [](FileBytes& f) { f.set<u32>(f.meta() + 48, f.voxel_count() + 1); }, "section VOXT size"},
      {"vert_size", meta_add(16, 1), "section VERT size"},
      {"vxln_size", meta_add(32, 1), "section VXLN size"},
      {"strm_size", meta_add(0, 1), "section STRM size"},
      {"strm_overflow", meta_u64(0, std::numeric_limits<u64>::max()), "section STRM size"},
      {"random_without_vdir", [](FileBytes& f) { f.set<u32>(f.meta() + 100, static_cast<u32>(OrderSet::Random)); },
       "order set random needs a VDIR section"},
  };
}

// The voxel table (spec §5.3).
std::vector<Case> voxel_table_cases() {
  return {
      {"coord_outside", [](FileBytes& f) { f.set<std::int32_t>(f.voxel(0), f.get<std::int32_t>(f.meta() + 88)); },
       "voxel coordinate outside the grid"},
      {"coord_order",
       [](FileBytes& f) {
         for (int c = 0; c < 3; ++c) {  // swap the coordinates of the first two voxels
           const auto a = f.get<std::int32_t>(f.voxel(0) + 4 * c), b = f.get<std::int32_t>(f.voxel(1) + 4 * c);
           f.set(f.voxel(0) + 4 * c, b);
           f.set(f.voxel(1) + 4 * c, a);
         }
       },
       "voxel coordinates not strictly increasing"},
      {"voxel_flags", [](FileBytes& f) { f.set<u32>(f.voxel(0) + 12, 3); },
       "voxel flags must hold the order width code"},
      {"no_vertices", [](FileBytes& f) { f.set<u32>(f.voxel(0) + 48, 0); }, "voxel with no vertices"},
      {"segments", [](FileBytes& f) { f.set<u32>(f.voxel(0) + 52, f.get<u32>(f.voxel(0) + 48)); },
       "voxel has as many segments as vertices"},
      {"contiguous", [](FileBytes& f) { f.set<u64>(f.voxel(1) + 40, f.get<u64>(f.voxel(1) + 40) + 1); },
       "voxel vertex blocks are not contiguous"},
      {"block_past_end",
       [](FileBytes& f) {
         const u64 last = f.voxel(f.voxel_count() - 1);
         f.set<u32>(last + 48, f.get<u32>(last + 48) + 1);
       },
       "voxel vertex block runs past vertex_count"},
      {"order_offset", [](FileBytes& f) { f.set<u64>(f.voxel(1) + 56, f.get<u64>(f.voxel(1) + 56) + 2); },
       "order offset not a multiple of 4 or decreasing"},
      {"orders_past_end", [](FileBytes& f) { f.set<u64>(f.voxel(f.voxel_count() - 1) + 56, u64(1) << 40); },
       "voxel orders run past the ORDB section"},
      {"blocks_short",
       [](FileBytes& f) {
         const u64 last = f.voxel(f.voxel_count() - 1);
         f.set<u32>(last + 48, f.get<u32>(last + 48) - 1);
         f.set<u32>(last + 52, f.get<u32>(last + 52) - 1);
       },
       "voxel blocks do not cover all vertices"},
      {"segment_sum", [](FileBytes& f) { f.set<u32>(f.voxel(0) + 52, f.get<u32>(f.voxel(0) + 52) - 1); },
       "voxel segment counts do not add up to segment_count"},
  };
}

// Levels of detail (spec §5.12; the base file has the default levels).
std::vector<Case> level_cases() {
  return {
      {"level_count_1", [](FileBytes& f) { f.set<u32>(f.meta() + 156, 1); }, "level count 1 must be 0 or 2..8"},
      {"level_count_9", [](FileBytes& f) { f.set<u32>(f.meta() + 156, 9); }, "level count 9 must be 0 or 2..8"},
      {"lods_without_level_count", [](FileBytes& f) { f.set<u32>(f.meta() + 156, 0); },
       "LODS section without a level count"},
      {"level_count_not_lods_size", [](FileBytes& f) { f.set<u32>(f.meta() + 156, 3); }, "section LODS size"},
      {"levels_in_2_0", [](FileBytes& f) { f.set<std::uint16_t>(10, 0); },
       "levels of detail in a file before version 2.1"},
      {"level_past_block", [](FileBytes& f) { f.set<u32>(f.section_at("LODS"), f.get<u32>(f.voxel(0) + 48) + 1); },
       "voxel 0 level 1 is not a prefix of level 0"},
      {"level_segments_without_vertices",
       [](FileBytes& f) {
         f.set<u32>(f.section_at("LODS"), 0);
         f.set<u32>(f.section_at("LODS") + 4, 1);
       },
       "voxel 0 level 1 is not a prefix of level 0"},
      {"coarser_level_past_finer",
       [](FileBytes& f) {
         const u64 row = f.section_at("LODS");  // voxel 0: levels 1, 2, ... at 8 bytes each
         f.set<u32>(row, 0);
         f.set<u32>(row + 4, 0);
         f.set<u32>(row + 8, 2);
         f.set<u32>(row + 12, 1);
       },
       "voxel 0 level 2 is not a prefix of level 1"},
  };
}

std::vector<Case> cases() {
  std::vector<Case> all;
  for (auto part : {position_cases, header_and_table_cases, meta_cases, voxel_table_cases, level_cases})
    for (Case& c : part()) all.push_back(std::move(c));
  return all;
}

class VxlValidation : public ::testing::TestWithParam<Case> {};

TEST_P(VxlValidation, OpenRefusesWithItsMessage) {
  ScratchDir dir;
  ConvertSettings settings;
  settings.voxel_size = 5;
  const std::string valid = dir.file("valid.vxl");
  convert_tractogram(crossing_tractogram(), valid, settings);
  FileBytes f{slurp(valid)};
  ASSERT_GE(f.voxel_count(), 3u) << "the test needs a few voxels";
  ASSERT_GE(f.get<std::uint32_t>(f.voxel(0) + 52), 1u) << "the first voxel needs a segment";
  ASSERT_NO_THROW(VxlFile::open(valid));

  const Case& c = GetParam();
  c.damage(f);
  test::reseal_checksums(f.b.data(), f.b.size());
  const std::string damaged = dir.file("damaged.vxl");
  std::ofstream(damaged, std::ios::binary).write(f.b.data(), static_cast<std::streamsize>(f.b.size()));
  try {
    VxlFile::open(damaged);
    FAIL() << c.name << ": opened";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << c.name << ": " << e.what();
    EXPECT_EQ(e.kind(), c.kind) << c.name << ": " << e.what();
    EXPECT_EQ(e.file(), damaged);
  }
}

INSTANTIATE_TEST_SUITE_P(EveryRefusal, VxlValidation, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace vxl
