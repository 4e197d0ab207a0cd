// Values per group (TRX dpg/, spec §5.13 GDAT): one row of values per (group, name), kept in the source's
// dtype so that export gives the source's bytes back. What the TRX reader fills, the .vxl and .vxlz carry
// and the TRX export writes: one struct and one encoding for all of them.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace vxl {

// The element types of spec §5.13 (TRX dtype names), by their codes in GDAT.
enum class GroupValueType : std::uint16_t {
  Uint8 = 1,
  Uint16,
  Uint32,
  Uint64,
  Int8,
  Int16,
  Int32,
  Int64,
  Float16,
  Float32,
  Float64,
};

// "uint8" … "float64"; nullopt for any other name.
std::optional<GroupValueType> group_value_type(const std::string& dtype);
const char* group_value_type_name(GroupValueType type);
std::size_t group_value_type_size(GroupValueType type);

struct GroupValues {
  std::uint32_t group = 0;  // index into the groups (GRPS order)
  std::string name;         // UTF-8, no NUL, no '/', not empty
  GroupValueType type = GroupValueType::Float32;
  std::uint32_t components = 1;     // values in the row
  std::vector<std::uint8_t> bytes;  // components × size(type) bytes, little-endian as in the source
};

// Values in one row at most: a TRX dpg is a colour, a volume, a matrix; never an array per streamline.
constexpr std::uint32_t kMaxGroupValueComponents = 1u << 20;
// Longest name (the TRX member name dpg/<group>/<name>.<n>.<dtype> must fit a zip entry's 16-bit length).
constexpr std::uint32_t kMaxGroupValueNameBytes = 4096;

// The GDAT payload (spec §5.13).
std::vector<std::uint8_t> encode_group_values(std::span<const GroupValues> values);

// Parses and checks a GDAT payload against the number of groups: `fail` is called with the byte position
// in `payload` and what is wrong, and must throw.
std::vector<GroupValues> decode_group_values(
    std::span<const std::uint8_t> payload, std::uint64_t group_count,
    const std::function<void(std::uint64_t position, const std::string& what)>& fail);

// "name.3.uint8" / "name.float16": the TRX file name of a row (the component count only when above 1).
std::string group_value_file_name(const GroupValues& v);

}  // namespace vxl
