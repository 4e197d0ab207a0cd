#include "format/vxl_group_values.h"

#include <cstring>
#include <set>
#include <utility>

#include "format/base/utf8_check.h"

namespace vxl {
namespace {

struct TypeInfo {
  GroupValueType type;
  const char* name;
  std::size_t size;
};
constexpr TypeInfo kTypes[] = {
    {GroupValueType::Uint8, "uint8", 1},     {GroupValueType::Uint16, "uint16", 2},
    {GroupValueType::Uint32, "uint32", 4},   {GroupValueType::Uint64, "uint64", 8},
    {GroupValueType::Int8, "int8", 1},       {GroupValueType::Int16, "int16", 2},
    {GroupValueType::Int32, "int32", 4},     {GroupValueType::Int64, "int64", 8},
    {GroupValueType::Float16, "float16", 2}, {GroupValueType::Float32, "float32", 4},
    {GroupValueType::Float64, "float64", 8},
};

const TypeInfo* info(std::uint16_t code) {
  for (const TypeInfo& t : kTypes)
    if (static_cast<std::uint16_t>(t.type) == code) return &t;
  return nullptr;
}

std::uint64_t align8(std::uint64_t n) { return (n + 7) & ~std::uint64_t{7}; }

}  // namespace

std::optional<GroupValueType> group_value_type(const std::string& dtype) {
  for (const TypeInfo& t : kTypes)
    if (dtype == t.name) return t.type;
  return std::nullopt;
}

const char* group_value_type_name(GroupValueType type) { return info(static_cast<std::uint16_t>(type))->name; }

std::size_t group_value_type_size(GroupValueType type) { return info(static_cast<std::uint16_t>(type))->size; }

std::string group_value_file_name(const GroupValues& v) {
  return v.name + (v.components > 1 ? "." + std::to_string(v.components) : std::string()) + "." +
         group_value_type_name(v.type);
}

std::vector<std::uint8_t> encode_group_values(std::span<const GroupValues> values) {
  std::vector<std::uint8_t> out;
  auto put = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  const std::uint32_t header[2] = {static_cast<std::uint32_t>(values.size()), 0};
  put(header, sizeof header);
  for (const GroupValues& v : values) {
    const std::uint16_t type[2] = {static_cast<std::uint16_t>(v.type), 0};
    const std::uint32_t name_length = static_cast<std::uint32_t>(v.name.size());
    put(&v.group, 4);
    put(type, 4);
    put(&v.components, 4);
    put(&name_length, 4);
    put(v.name.data(), v.name.size());
    out.resize(align8(out.size()), 0);
    put(v.bytes.data(), v.bytes.size());
    out.resize(align8(out.size()), 0);
  }
  return out;
}

std::vector<GroupValues> decode_group_values(
    std::span<const std::uint8_t> payload, std::uint64_t group_count,
    const std::function<void(std::uint64_t position, const std::string& what)>& fail) {
  std::uint64_t pos = 0;
  auto need = [&](std::uint64_t n, const char* what) {
    if (n > payload.size() - pos) fail(pos, std::string("GDAT truncated in ") + what);
  };
  auto u32 = [&](const char* what) {
    need(4, what);
    std::uint32_t v;
    std::memcpy(&v, payload.data() + pos, 4);
    pos += 4;
    return v;
  };
  // Padding and reserved fields are zero, so that one content has one encoding (verify covers every byte).
  auto zeros_to = [&](std::uint64_t end, const char* what) {
    need(end - pos, what);
    for (; pos < end; ++pos)
      if (payload[pos] != 0) fail(pos, std::string("GDAT ") + what + " is not zero");
  };
  const std::uint32_t count = u32("the header");
  if (u32("the header") != 0) fail(4, "GDAT reserved field is not zero");
  // Every entry takes at least 24 bytes: a count the payload cannot hold is refused before allocating.
  if (count > (payload.size() - pos) / 24) fail(0, "GDAT entry count runs past the section");
  std::vector<GroupValues> out;
  out.reserve(count);
  std::set<std::pair<std::uint32_t, std::string>> seen;
  for (std::uint32_t e = 0; e < count; ++e) {
    const std::uint64_t at = pos;
    GroupValues v;
    v.group = u32("an entry");
    if (v.group >= group_count)
      fail(at, "GDAT entry " + std::to_string(e) + " names group " + std::to_string(v.group) + " of " +
                   std::to_string(group_count));
    const std::uint32_t type = u32("an entry");
    const TypeInfo* t = info(static_cast<std::uint16_t>(type & 0xFFFF));
    if (t == nullptr || (type >> 16) != 0)
      fail(at + 4, "GDAT entry " + std::to_string(e) + " has an unknown element type " + std::to_string(type));
    v.type = t->type;
    v.components = u32("an entry");
    if (v.components == 0 || v.components > kMaxGroupValueComponents)
      fail(at + 8, "GDAT entry " + std::to_string(e) + " has " + std::to_string(v.components) +
                       " components (expected 1 … " + std::to_string(kMaxGroupValueComponents) + ")");
    const std::uint32_t name_length = u32("an entry");
    if (name_length == 0 || name_length > kMaxGroupValueNameBytes)
      fail(at + 12, "GDAT entry " + std::to_string(e) + " has a name of " + std::to_string(name_length) +
                        " bytes (expected 1 … " + std::to_string(kMaxGroupValueNameBytes) + ")");
    need(name_length, "a name");
    v.name.assign(reinterpret_cast<const char*>(payload.data() + pos), name_length);
    if (v.name.find_first_of(std::string("/\0", 2)) != std::string::npos || !is_valid_utf8(v.name))
      fail(pos, "GDAT entry " + std::to_string(e) + " name is not UTF-8 without '/' and NUL");
    pos += name_length;
    zeros_to(align8(pos), "name padding");
    const std::uint64_t bytes = std::uint64_t{v.components} * t->size;
    need(bytes, "the values");
    v.bytes.assign(payload.begin() + static_cast<std::ptrdiff_t>(pos),
                   payload.begin() + static_cast<std::ptrdiff_t>(pos + bytes));
    pos += bytes;
    zeros_to(align8(pos), "value padding");
    if (!seen.emplace(v.group, v.name).second)
      fail(at, "GDAT holds '" + v.name + "' twice for group " + std::to_string(v.group));
    out.push_back(std::move(v));
  }
  if (pos != payload.size()) fail(pos, "GDAT has bytes after its last entry");
  return out;
}

}  // namespace vxl
