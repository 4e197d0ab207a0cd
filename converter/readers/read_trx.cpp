// TRX reader (zip archive, stored or deflated, or the same layout as a plain directory).
//
// Coordinate convention: TRX positions are already world coordinates, RAS mm, so they are taken as-is:
// float32 bit-exactly, float16 widened exactly, float64 rounded to nearest float32 (with a warning).
// VOXEL_TO_RASMM in header.json describes the reference image only; it is kept as provenance and is
// not applied.
//
// Members used: header.json (NB_STREAMLINES, NB_VERTICES, VOXEL_TO_RASMM, DIMENSIONS),
// positions.3.<float16|float32|float64>, offsets.<uint32|uint64> and groups/<name>.<integer dtype>;
// all little-endian. dpv/<name>[.<n>].<dtype> and dps/<name>[.<n>].<dtype> (any float or integer dtype)
// become per-point and per-streamline value sets (one per component: name[0] ... name[n-1]);
// dpg/<group>/<name>[.<n>].<dtype> become rows of values per group, kept in their dtype. A group is a set:
// an index listed twice in one groups/ member counts once, with a warning giving how many were collapsed.
// All member names are listed in the header JSON under "_members". Offsets come in two conventions: N + 1 entries
// ending with the NB_VERTICES sentinel (current trx-python), or N entries without it (older files); both are accepted.
#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "converter/readers/float16.h"
#include "converter/readers/latin1.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/regular_file.h"
#include "converter/readers/trx_members.h"
#include "format/base/checksum.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/base/mapped_file.h"

namespace vxl {
namespace {

using trx::Blob;
using trx::Members;

// ---- little-endian loads ----

template <typename T>
T load_le(const std::uint8_t* p) {
  using U = std::conditional_t<sizeof(T) == 1, std::uint8_t,
                               std::conditional_t<sizeof(T) == 2, std::uint16_t,
                                                  std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
  U u = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) u |= static_cast<U>(static_cast<U>(p[i]) << (8 * i));
  return std::bit_cast<T>(u);
}

// a * b, or the largest uint64 where that overflows (a size no archive can have).
std::uint64_t times(std::uint64_t a, std::uint64_t b) {
  return b != 0 && a > ~std::uint64_t{0} / b ? ~std::uint64_t{0} : a * b;
}

// header.json holds a handful of keys; real ones are a few hundred bytes.
constexpr std::uint64_t kMaxHeaderJson = 16u << 20;

// JSON strings must be UTF-8; member names from a directory or an old zip may not be.
std::string json_safe(const std::string& s) {
  try {
    (void)nlohmann::json(s).dump();
    return s;
  } catch (const nlohmann::json::exception&) {
    return latin1_to_utf8(s);
  }
}

std::optional<std::uint64_t> json_count(const nlohmann::json& v) {
  if (v.is_number_unsigned()) return v.get<std::uint64_t>();
  if (v.is_number_integer() && v.get<std::int64_t>() >= 0) return static_cast<std::uint64_t>(v.get<std::int64_t>());
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (d >= 0 && d < 1.8e19 && std::floor(d) == d) return static_cast<std::uint64_t>(d);
  }
  return std::nullopt;
}

// The single member named <prefix><dtype> at the archive root, e.g. "offsets.uint64".
std::optional<std::string> find_root_member(const std::string& path, const Members& m, const std::string& prefix) {
  std::optional<std::string> found;
  for (const auto& [name, index] : m.names()) {
    if (!name.starts_with(prefix) || name.find('/') != std::string::npos) continue;
    if (found) fail_input(path, std::nullopt, "two candidate members " + *found + " and " + name);
    found = name;
  }
  return found;
}

std::size_t integer_dtype_size(const std::string& dtype, bool& is_signed) {
  static const std::map<std::string, std::pair<std::size_t, bool>> kTypes = {
      {"uint8", {1, false}}, {"uint16", {2, false}}, {"uint32", {4, false}}, {"uint64", {8, false}},
      {"int8", {1, true}},   {"int16", {2, true}},   {"int32", {4, true}},   {"int64", {8, true}}};
  auto it = kTypes.find(dtype);
  if (it == kTypes.end()) return 0;
  is_signed = it->second.second;
  return it->second.first;
}

// Loads one little-endian integer of `size` bytes; a negative value comes back as nullopt.
std::optional<std::uint64_t> load_index(const std::uint8_t* p, std::size_t size, bool is_signed) {
  if (!is_signed) {
    switch (size) {
      case 1: return load_le<std::uint8_t>(p);
      case 2: return load_le<std::uint16_t>(p);
      case 4: return load_le<std::uint32_t>(p);
      default: return load_le<std::uint64_t>(p);
    }
  }
  std::int64_t v = 0;
  switch (size) {
    case 1: v = load_le<std::int8_t>(p); break;
    case 2: v = load_le<std::int16_t>(p); break;
    case 4: v = load_le<std::int32_t>(p); break;
    default: v = load_le<std::int64_t>(p); break;
  }
  if (v < 0) return std::nullopt;
  return static_cast<std::uint64_t>(v);
}

void read_positions(const std::string& path, const std::string& member, const std::string& dtype,
                    std::span<const std::uint8_t> bytes, std::uint64_t nb_vertices, Tractogram& t) {
  const std::size_t elem = dtype == "float16" ? 2 : dtype == "float32" ? 4 : 8;
  if (bytes.size() % (3 * elem) != 0 || bytes.size() / (3 * elem) != nb_vertices)
    fail_input(path, std::nullopt,
               member + ": holds " + std::to_string(bytes.size()) +
                   " bytes but NB_VERTICES = " + std::to_string(nb_vertices) + " needs " + std::to_string(nb_vertices) +
                   " x 3 x " + std::to_string(elem));
  const std::size_t n = bytes.size() / elem;
  t.positions.resize(n);
  const std::uint8_t* p = bytes.data();
  for (std::size_t i = 0; i < n; ++i, p += elem) {
    float v;
    if (elem == 2)
      v = half_to_float(load_le<std::uint16_t>(p));
    else if (elem == 4)
      v = load_le<float>(p);
    else
      v = static_cast<float>(load_le<double>(p));
    if (!std::isfinite(v))
      fail_input(path, std::nullopt,
                 member + ": vertex " + std::to_string(i / 3) + " has a non-finite coordinate" +
                     (elem == 8 ? " (or one beyond the float32 range)" : ""));
    t.positions[i] = v;
  }
  if (elem == 8) t.source.warnings.push_back(member + ": float64 positions rounded to float32");
}

void read_offsets(const std::string& path, const std::string& member, const std::string& dtype,
                  std::span<const std::uint8_t> bytes, std::uint64_t nb_streamlines, std::uint64_t nb_vertices,
                  Tractogram& t) {
  const std::size_t elem = dtype == "uint32" ? 4 : 8;
  if (bytes.size() % elem != 0)
    fail_input(path, std::nullopt,
               member + ": size " + std::to_string(bytes.size()) + " is not a multiple of " + std::to_string(elem));
  const std::uint64_t m = bytes.size() / elem;
  auto entry = [&](std::uint64_t i) {
    const std::uint8_t* p = bytes.data() + i * elem;
    return elem == 4 ? std::uint64_t{load_le<std::uint32_t>(p)} : load_le<std::uint64_t>(p);
  };
  const std::string expected = "NB_STREAMLINES = " + std::to_string(nb_streamlines) + " needs " +
                               std::to_string(nb_streamlines) + " entries (no sentinel) or " +
                               std::to_string(nb_streamlines + 1) +
                               " ending with NB_VERTICES = " + std::to_string(nb_vertices);
  std::uint64_t starts = 0;  // entries that are streamline starts; NB_VERTICES closes the last one
  if (m == nb_streamlines) {
    starts = m;  // the older convention without the sentinel
  } else if (m > 0 && m - 1 == nb_streamlines) {
    const std::uint64_t last = entry(m - 1);
    if (last == nb_vertices) {
      starts = nb_streamlines;  // the sentinel convention
    } else if (last < nb_vertices) {
      // N + 1 entries whose last is below NB_VERTICES cannot end with a sentinel (vertices would be left
      // outside every streamline): they are N + 1 starts and header.json's NB_STREAMLINES is one short.
      // Seen in niivue's demos/images/dpsv.trx, which holds the same 460 streamlines as the older
      // tests/images/dpsv.trx but says NB_STREAMLINES = 459.
      starts = m;
      t.source.warnings.push_back(
          member + ": " + std::to_string(m) + " entries and the last (" + std::to_string(last) +
          ") is below NB_VERTICES (" + std::to_string(nb_vertices) + "), so it is no sentinel; reading " +
          std::to_string(m) +
          " streamlines although header.json says NB_STREAMLINES = " + std::to_string(nb_streamlines));
    } else {
      fail_input(path, std::nullopt,
                 member + ": the last entry (" + std::to_string(last) + ") points past the " +
                     std::to_string(nb_vertices) + " vertices");
    }
  } else {
    fail_input(path, std::nullopt, member + ": has " + std::to_string(m) + " entries; " + expected);
  }
  t.offsets.resize(starts + 1);
  for (std::uint64_t i = 0; i < starts; ++i) t.offsets[i] = entry(i);
  t.offsets[starts] = nb_vertices;
  if (starts == 0 && nb_vertices != 0)
    fail_input(path, std::nullopt, member + ": no streamlines but NB_VERTICES = " + std::to_string(nb_vertices));
  if (starts > 0 && t.offsets[0] != 0)
    fail_input(path, std::nullopt, member + ": the first offset is " + std::to_string(t.offsets[0]) + ", not 0");
  for (std::uint64_t i = 0; i < starts; ++i) {
    if (t.offsets[i] > t.offsets[i + 1]) {
      if (i + 1 == starts)
        fail_input(path, std::nullopt,
                   member + ": entry " + std::to_string(i) + " (" + std::to_string(t.offsets[i]) +
                       ") points past the " + std::to_string(nb_vertices) + " vertices");
      fail_input(path, std::nullopt,
                 member + ": offsets decrease at entry " + std::to_string(i + 1) + " (" + std::to_string(t.offsets[i]) +
                     " then " + std::to_string(t.offsets[i + 1]) + ")");
    }
  }
}

void read_groups(const std::string& path, const Members& members, Tractogram& t) {
  const std::uint64_t n = t.streamline_count();
  for (const auto& [name, index] : members.names()) {
    if (!name.starts_with("groups/")) continue;
    const std::string rest = name.substr(7);
    const std::size_t dot = rest.rfind('.');
    if (rest.find('/') != std::string::npos || dot == std::string::npos || dot == 0) {
      t.source.warnings.push_back(name + ": not a groups/<name>.<dtype> member; ignored");
      continue;
    }
    bool is_signed = false;
    const std::size_t elem = integer_dtype_size(rest.substr(dot + 1), is_signed);
    if (elem == 0)
      fail_input(path, std::nullopt, name + ": group indices must be of an integer dtype (uint8 ... int64)");
    const Blob blob = members.read(name, times(n, elem),
                                   "bytes a group of the " + std::to_string(n) + " streamlines can list (each once)");
    const auto bytes = blob.bytes();
    if (bytes.size() % elem != 0)
      fail_input(path, std::nullopt,
                 name + ": size " + std::to_string(bytes.size()) + " is not a multiple of " + std::to_string(elem));
    StreamlineGroup g;
    g.name = json_safe(rest.substr(0, dot));
    g.members.reserve(bytes.size() / elem);
    for (std::size_t i = 0; i < bytes.size() / elem; ++i) {
      const auto v = load_index(bytes.data() + i * elem, elem, is_signed);
      if (!v || *v >= n)
        fail_input(path, std::nullopt,
                   name + ": entry " + std::to_string(i) + " is not a streamline index below " + std::to_string(n));
      g.members.push_back(*v);
    }
    std::sort(g.members.begin(), g.members.end());
    const std::size_t listed = g.members.size();
    g.members.erase(std::unique(g.members.begin(), g.members.end()), g.members.end());
    // Membership is a set (spec §5.9 stores strictly increasing members): a repeat adds nothing to the
    // group, but it may be a mistake in the source, so it is said, not silently dropped.
    if (const std::size_t repeats = listed - g.members.size(); repeats > 0)
      t.source.warnings.push_back("group " + g.name + ": " + std::to_string(repeats) +
                                  " duplicate indices collapsed (" + std::to_string(listed) + " listed in " +
                                  json_safe(name) + ", " + std::to_string(g.members.size()) + " streamlines)");
    t.groups.push_back(std::move(g));
  }
}

// A float or integer dtype's element size, 0 when unknown.
std::size_t value_dtype_size(const std::string& dtype) {
  bool is_signed = false;
  if (dtype == "float16") return 2;
  if (dtype == "float32") return 4;
  if (dtype == "float64") return 8;
  return integer_dtype_size(dtype, is_signed);
}

float load_value(const std::uint8_t* p, const std::string& dtype) {
  if (dtype == "float16") return half_to_float(load_le<std::uint16_t>(p));
  if (dtype == "float32") return load_le<float>(p);
  if (dtype == "float64") return static_cast<float>(load_le<double>(p));
  if (dtype == "uint8") return load_le<std::uint8_t>(p);
  if (dtype == "uint16") return load_le<std::uint16_t>(p);
  if (dtype == "uint32") return static_cast<float>(load_le<std::uint32_t>(p));
  if (dtype == "uint64") return static_cast<float>(load_le<std::uint64_t>(p));
  if (dtype == "int8") return load_le<std::int8_t>(p);
  if (dtype == "int16") return load_le<std::int16_t>(p);
  if (dtype == "int32") return static_cast<float>(load_le<std::int32_t>(p));
  return static_cast<float>(load_le<std::int64_t>(p));
}

// dpv/ or dps/ members -> value sets of `count` entries each. A member that cannot be read as such (no
// dtype, a size that does not match) is skipped with a warning: the streamlines are still good.
void read_value_sets(const std::string& path, const Members& members, const std::string& folder, std::uint64_t count,
                     Tractogram& t, std::vector<ValueSet>& out) {
  for (const auto& [name, index] : members.names()) {
    if (!name.starts_with(folder)) continue;
    const std::string rest = name.substr(folder.size());
    const std::size_t dot = rest.rfind('.');
    const std::string dtype = dot == std::string::npos ? "" : rest.substr(dot + 1);
    const std::size_t elem = value_dtype_size(dtype);
    if (rest.find('/') != std::string::npos || dot == std::string::npos || dot == 0 || elem == 0) {
      t.source.warnings.push_back(json_safe(name) + ": not " + folder + "<name>[.<components>].<dtype>; ignored");
      continue;
    }
    std::string base = rest.substr(0, dot);
    std::uint64_t components = 1;
    if (const std::size_t d2 = base.rfind('.'); d2 != std::string::npos && d2 > 0 && d2 + 1 < base.size() &&
                                                base.find_first_not_of("0123456789", d2 + 1) == std::string::npos) {
      // Digits only, but any number of them: a count beyond 64 bits is malformed, not an internal error.
      const std::string digits = base.substr(d2 + 1);
      const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), components);
      if (ec != std::errc() || end != digits.data() + digits.size())
        fail_input(path, std::nullopt, json_safe(name) + ": the component count " + digits + " is out of range");
      base = base.substr(0, d2);
    }
    // The size is judged before inflating anything: the counts fix it exactly.
    const std::uint64_t declared = members.declared_size(name);
    const std::uint64_t expected = times(times(count, components), elem);
    if (components == 0 || components > 64 || declared != expected) {
      t.source.warnings.push_back(json_safe(name) + ": holds " + std::to_string(declared) + " bytes, expected " +
                                  std::to_string(count) + " x " + std::to_string(components) + " x " +
                                  std::to_string(elem) + "; ignored");
      continue;
    }
    const Blob blob = members.read(name, expected, "bytes its counts need");
    const auto bytes = blob.bytes();
    if (bytes.size() != expected) {
      t.source.warnings.push_back(json_safe(name) + ": holds " + std::to_string(bytes.size()) + " bytes, expected " +
                                  std::to_string(expected) + "; ignored");
      continue;
    }
    while (!base.empty() && base.back() == ' ') base.pop_back();  // seen in niivue's colby.trx: "effect   .float32"
    for (std::uint64_t c = 0; c < components; ++c) {
      ValueSet v;
      v.name = json_safe(base) + (components > 1 ? "[" + std::to_string(c) + "]" : "");
      v.values.resize(count);
      for (std::uint64_t i = 0; i < count; ++i)
        v.values[i] = load_value(bytes.data() + (i * components + c) * elem, dtype);
      out.push_back(std::move(v));
    }
  }
}

// dpg/<group>/<name>[.<n>].<dtype> members -> one row of n values per group and name, kept as bytes in their
// dtype. A member that cannot be read as such (no such group, no dtype, a size that does not match) is
// skipped with a warning, like a malformed dpv or dps: the streamlines are still good.
void read_group_values(const Members& members, Tractogram& t) {
  // Looked up by name, and rows seen, in O(log n): an archive may hold many members.
  std::map<std::string, std::uint32_t> group_by_name;
  for (std::size_t g = t.groups.size(); g-- > 0;) group_by_name[t.groups[g].name] = static_cast<std::uint32_t>(g);
  std::set<std::pair<std::uint32_t, std::string>> seen;
  for (const auto& [name, index] : members.names()) {
    if (!name.starts_with("dpg/")) continue;
    const std::string rest = name.substr(4);
    const std::size_t slash = rest.find('/');
    const std::string group = slash == std::string::npos ? "" : rest.substr(0, slash);
    const std::string file = slash == std::string::npos ? "" : rest.substr(slash + 1);
    const std::size_t dot = file.rfind('.');
    // A plain value and a flag, not an optional: GCC 12 takes the optional's value for uninitialised.
    GroupValueType type{};
    bool typed = false;
    if (dot != std::string::npos)
      if (const std::optional<GroupValueType> known = group_value_type(file.substr(dot + 1))) {
        type = *known;
        typed = true;
      }
    if (group.empty() || file.find('/') != std::string::npos || dot == std::string::npos || dot == 0 || !typed) {
      t.source.warnings.push_back(json_safe(name) + ": not dpg/<group>/<name>[.<components>].<dtype>; ignored");
      continue;
    }
    std::string base = file.substr(0, dot);
    std::uint64_t components = 1;
    if (const std::size_t d2 = base.rfind('.'); d2 != std::string::npos && d2 > 0 && d2 + 1 < base.size() &&
                                                base.find_first_not_of("0123456789", d2 + 1) == std::string::npos) {
      const std::string digits = base.substr(d2 + 1);
      const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), components);
      if (ec != std::errc() || end != digits.data() + digits.size()) components = 0;  // refused below
      base = base.substr(0, d2);
    }
    const auto owner = group_by_name.find(json_safe(group));  // the first group of that name
    if (owner == group_by_name.end()) {
      t.source.warnings.push_back(json_safe(name) + ": no groups/" + json_safe(group) + ".<dtype> member; ignored");
      continue;
    }
    const std::string row_name = json_safe(base);
    const std::uint32_t group_index = owner->second;
    if (row_name.size() > kMaxGroupValueNameBytes) {
      t.source.warnings.push_back(json_safe(name) + ": a name longer than " + std::to_string(kMaxGroupValueNameBytes) +
                                  " bytes; ignored");
      continue;
    }
    if (seen.contains({group_index, row_name})) {
      t.source.warnings.push_back(json_safe(name) + ": a second dpg/" + json_safe(group) + "/" + row_name +
                                  " with another dtype or component count; ignored");
      continue;
    }
    const std::uint64_t elem = group_value_type_size(type);
    const std::uint64_t declared = members.declared_size(name);
    const std::uint64_t expected = times(components, elem);
    if (components == 0 || components > kMaxGroupValueComponents || declared != expected) {
      t.source.warnings.push_back(json_safe(name) + ": holds " + std::to_string(declared) +
                                  " bytes, expected one row of " + std::to_string(components) + " x " +
                                  std::to_string(elem) + "; ignored");
      continue;
    }
    const Blob blob = members.read(name, expected, "bytes its row needs");
    if (blob.bytes().size() != expected) {
      t.source.warnings.push_back(json_safe(name) + ": holds " + std::to_string(blob.bytes().size()) +
                                  " bytes, expected " + std::to_string(expected) + "; ignored");
      continue;
    }
    GroupValues v;
    v.group = group_index;
    v.name = row_name;
    v.type = type;
    v.components = static_cast<std::uint32_t>(components);
    v.bytes.assign(blob.bytes().begin(), blob.bytes().end());
    seen.emplace(group_index, row_name);
    t.group_values.push_back(std::move(v));
  }
}

}  // namespace

Tractogram read_trx(const std::string& path) {
  Tractogram t;
  t.source.path = path;
  t.source.format = "trx";

  require_regular_file(path, /*allow_directory=*/true);
  std::optional<MappedFile> zip_file;
  std::unique_ptr<Members> members;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    members = trx::dir_members(path);
    // Directory provenance: the member files' bytes in byte-wise order of their relative paths
    // (std::string compares as unsigned bytes), so the hash does not depend on listing order.
    Xxh3_128Stream hash;
    for (const auto& [name, index] : members->names()) {
      const Blob blob = members->read(name, ~std::uint64_t{0}, "");  // mapped: no memory to bound
      hash.update(blob.bytes().data(), blob.bytes().size());
      t.source.bytes += blob.bytes().size();
    }
    t.source.xxh3_128 = hash.hex();
  } else {
    zip_file.emplace(path);
    t.source.bytes = zip_file->size();
    t.source.xxh3_128 = xxh3_128_hex(zip_file->data(), zip_file->size());
    members = trx::zip_members(path, zip_file->bytes());
  }

  // header.json
  if (!members->has("header.json")) fail_input(path, std::nullopt, "missing member header.json");
  nlohmann::json header;
  {
    const Blob blob = members->read("header.json", kMaxHeaderJson, "bytes a header.json may have");
    const auto bytes = blob.bytes();
    header = parse_json({reinterpret_cast<const char*>(bytes.data()), bytes.size()}, path, std::nullopt, "header.json",
                        kMaxSourceJsonDepth);
  }
  if (header.is_discarded() || !header.is_object()) fail_input(path, std::nullopt, "header.json: not a JSON object");
  auto required_count = [&](const char* key) {
    const auto it = header.find(key);
    if (it == header.end()) fail_input(path, std::nullopt, std::string("header.json: missing ") + key);
    const auto v = json_count(*it);
    if (!v) fail_input(path, std::nullopt, std::string("header.json: ") + key + " is not a non-negative integer");
    return *v;
  };
  const std::uint64_t nb_streamlines = required_count("NB_STREAMLINES");
  const std::uint64_t nb_vertices = required_count("NB_VERTICES");
  if (const auto it = header.find("VOXEL_TO_RASMM"); it != header.end()) {
    std::array<double, 16> m{};
    bool ok = it->is_array() && it->size() == 4;
    for (std::size_t i = 0; ok && i < 4; ++i) {
      const auto& row = (*it)[i];
      ok = row.is_array() && row.size() == 4;
      for (std::size_t j = 0; ok && j < 4; ++j) {
        ok = row[j].is_number();
        if (ok) m[4 * i + j] = row[j].get<double>();
      }
    }
    if (ok)
      t.source.vox_to_ras = m;
    else
      t.source.warnings.push_back("header.json: VOXEL_TO_RASMM is not a 4x4 array of numbers; ignored");
  } else {
    t.source.warnings.push_back("header.json: no VOXEL_TO_RASMM");
  }

  // positions.3.<dtype>
  const auto positions = find_root_member(path, *members, "positions.");
  if (!positions) fail_input(path, std::nullopt, "missing member positions.3.<float16|float32|float64>");
  std::string pos_dtype;
  for (const char* d : {"float16", "float32", "float64"})
    if (*positions == std::string("positions.3.") + d) pos_dtype = d;
  if (pos_dtype.empty())
    fail_input(path, std::nullopt, *positions + ": positions must be named positions.3.<float16|float32|float64>");
  t.source.dtype = pos_dtype;

  // offsets.<dtype>
  const auto offsets = find_root_member(path, *members, "offsets.");
  if (!offsets) fail_input(path, std::nullopt, "missing member offsets.<uint32|uint64>");
  if (*offsets != "offsets.uint32" && *offsets != "offsets.uint64")
    fail_input(path, std::nullopt, *offsets + ": offsets must be named offsets.uint32 or offsets.uint64");

  {
    const std::uint64_t elem = *offsets == "offsets.uint32" ? 4 : 8;
    const std::uint64_t entries = nb_streamlines == ~std::uint64_t{0} ? nb_streamlines : nb_streamlines + 1;
    const Blob blob = members->read(*offsets, times(entries, elem),
                                    "bytes that NB_STREAMLINES = " + std::to_string(nb_streamlines) + " allows (" +
                                        "at most NB_STREAMLINES + 1 entries of " + std::to_string(elem) + " bytes)");
    read_offsets(path, *offsets, offsets->substr(8), blob.bytes(), nb_streamlines, nb_vertices, t);
  }
  {
    const std::uint64_t elem = pos_dtype == "float16" ? 2 : pos_dtype == "float32" ? 4 : 8;
    const Blob blob = members->read(*positions, times(times(nb_vertices, 3), elem),
                                    "bytes that NB_VERTICES = " + std::to_string(nb_vertices) + " needs (3 x " +
                                        std::to_string(elem) + " bytes per vertex)");
    read_positions(path, *positions, pos_dtype, blob.bytes(), nb_vertices, t);
  }
  read_groups(path, *members, t);
  read_value_sets(path, *members, "dpv/", t.point_count(), t, t.point_values);
  read_value_sets(path, *members, "dps/", t.streamline_count(), t, t.streamline_values);
  read_group_values(*members, t);

  nlohmann::json names = nlohmann::json::array();
  for (const auto& [name, index] : members->names()) names.push_back(json_safe(name));
  header["_members"] = std::move(names);
  t.source.header = std::move(header);
  return t;
}

}  // namespace vxl
