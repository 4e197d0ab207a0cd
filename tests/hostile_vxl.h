// The hostile .vxl generator: a valid file with every optional section (PROV, GRPS, VVAL, SVAL), made by
// converting a tractogram with groups and values per point and per streamline, and the byte surgery the
// hostile-input tests do to it (flip a byte, overwrite a field, recompute the checksums so that the
// damage gets past them). Nothing is committed as data: every damaged file is made here, in the test.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "converter/convert/convert.h"
#include "format/vxl_layout.h"
#include "format/vxl_value_sets.h"
#include "tests/reseal_checksums.h"
#include "tests/test_support.h"

namespace vxl::test {

// 40 streamlines of 6 points 3 mm apart (several voxels at 10 mm), two groups, one value set per point
// and one per streamline.
inline Tractogram hostile_source() {
  Tractogram t;
  t.source.path = "hostile.trx";
  t.source.format = "trx";
  for (int s = 0; s < 40; ++s) {
    std::vector<float> pts;
    for (int i = 0; i < 6; ++i) pts.insert(pts.end(), {3.0f * i - 8, 1.5f * s - 30, 0.25f * i * s});
    t.add_streamline(pts.data(), 6);
  }
  t.groups.push_back({"CST_left", {0, 2, 5, 39}});
  t.groups.push_back({"AF right", {1, 3}});
  ValueSet fa{"fa", {}};
  for (std::uint64_t i = 0; i < t.point_count(); ++i) fa.values.push_back(0.001f * static_cast<float>(i));
  t.point_values.push_back(fa);
  ValueSet length{"length", {}};
  for (std::uint64_t s = 0; s < t.streamline_count(); ++s) length.values.push_back(float(s));
  t.streamline_values.push_back(length);
  return t;
}

class VxlBytes {
 public:
  // Converts hostile_source() (at `voxel_size` mm) to `path` and reads the file's bytes.
  static VxlBytes make(const std::string& path, double voxel_size = 10.0) {
    ConvertSettings s;
    s.voxel_size = voxel_size;
    convert_tractogram(hostile_source(), path, s);
    VxlBytes b;
    b.bytes = test::slurp(path);
    return b;
  }

  // Where the section table entry of `id` (4 characters) is (ADD_FAILURE and 0 when absent).
  std::uint64_t entry_at(const char* id) const {
    FileHeader h;
    std::memcpy(&h, bytes.data(), sizeof h);
    for (std::uint32_t i = 0; i < h.section_count; ++i) {
      const std::uint64_t at = sizeof h + std::uint64_t(i) * sizeof(SectionEntry);
      if (std::memcmp(bytes.data() + at, id, 4) == 0) return at;
    }
    ADD_FAILURE() << "no section " << id;
    return 0;
  }
  SectionEntry entry(const char* id) const {
    SectionEntry e;
    std::memcpy(&e, bytes.data() + entry_at(id), sizeof e);
    return e;
  }
  std::uint64_t offset_of(const char* id) const { return entry(id).offset; }

  // Offsets of the name bytes of every group (GRPS, spec §5.9) and of every value set in `id` (VVAL,
  // SVAL, spec §5.11).
  std::vector<std::uint64_t> group_name_bytes() const {
    std::vector<std::uint64_t> out;
    std::uint64_t pos = offset_of("GRPS");
    std::uint32_t groups;
    std::memcpy(&groups, bytes.data() + pos, 4);
    pos += 8;
    for (std::uint32_t g = 0; g < groups; ++g) {
      std::uint32_t len;
      std::memcpy(&len, bytes.data() + pos, 4);
      pos += 4;
      for (std::uint32_t k = 0; k < len; ++k) out.push_back(pos + k);
      pos = align_up(pos + len, 8);
      std::uint64_t count;
      std::memcpy(&count, bytes.data() + pos, 8);
      pos += 8 + 8 * count;
    }
    return out;
  }
  std::vector<std::uint64_t> value_name_bytes(const char* id) const {
    std::vector<std::uint64_t> out;
    const std::uint64_t at = offset_of(id);
    ValueSetsHeader h;
    std::memcpy(&h, bytes.data() + at, sizeof h);
    for (std::uint32_t k = 0; k < h.set_count; ++k) {
      const std::uint64_t name_at = at + sizeof h + k * sizeof(ValueSetEntry);
      for (std::uint64_t i = 0; bytes[name_at + i] != 0; ++i) out.push_back(name_at + i);
    }
    return out;
  }

  void flip(std::uint64_t at, std::uint8_t mask = 0x80) { bytes[at] = static_cast<char>(bytes[at] ^ mask); }
  void reseal() { ASSERT_TRUE(reseal_checksums(bytes.data(), bytes.size())); }
  void write(const std::string& path) const {
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }

  std::vector<char> bytes;
};

// A valid file whose PROV holds, in the source's header, arrays nested `depth` deep (`depth` + 3 in all),
// checksums resealed: the converter writes no such PROV, a hand-made file can. The header's string that
// the conversion wrote is replaced by as many brackets, so no offset moves.
inline VxlBytes vxl_with_deep_provenance(const std::string& path, std::size_t depth) {
  Tractogram t = hostile_source();
  const std::string pad(2 * depth, 'x');
  t.source.header = {{"deep", pad}};
  convert_tractogram(std::move(t), path, {});
  VxlBytes b;
  b.bytes = test::slurp(path);
  const std::string quoted = '"' + pad + '"';
  const auto at = std::search(b.bytes.begin(), b.bytes.end(), quoted.begin(), quoted.end());
  EXPECT_NE(at, b.bytes.end());
  if (at == b.bytes.end()) return b;
  const std::string deep = std::string(depth, '[') + std::string(depth, ']') + "  ";
  std::copy(deep.begin(), deep.end(), at);
  b.reseal();
  return b;
}

}  // namespace vxl::test
