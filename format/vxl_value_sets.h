// The value-set sections (spec §5.11): `VVAL`, per-vertex values aligned with `VERT`, and `SVAL`,
// per-streamline values aligned with `STRM`. Both have the same layout:
//
//   offset 0                     ValueSetsHeader  {u32 set_count (1..64), u32 reserved = 0, u64 value_count}
//   offset 16                    set_count x ValueSetEntry {u8 name[48] (UTF-8, NUL-padded, >= 1 NUL),
//                                                           f32 min, f32 max, u64 reserved = 0}
//   value_sets_data_offset(n)    set_count arrays of value_count f32, array k at data_offset + k * stride,
//                                stride = value_count * 4 rounded up to 64; padding zero
//
// so that each array starts 64-byte aligned in the file and a chunk of vertices' values is one copy to
// the GPU, like the positions. min and max are over the array's finite values (both NaN when it has none).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "format/vxl_layout.h"

namespace vxl {

struct ValueSetsHeader {
  std::uint32_t set_count;
  std::uint32_t reserved;
  std::uint64_t value_count;
};
static_assert(sizeof(ValueSetsHeader) == 16);

struct ValueSetEntry {
  char name[48];
  float min;
  float max;
  std::uint64_t reserved;
};
static_assert(sizeof(ValueSetEntry) == 64);
static_assert(offsetof(ValueSetEntry, min) == 48);

inline constexpr std::uint32_t kMaxValueSets = 64;
inline constexpr std::size_t kMaxValueSetName = sizeof(ValueSetEntry::name) - 1;  // bytes, without the NUL

constexpr std::uint64_t value_sets_data_offset(std::uint64_t sets) {
  return align_up(sizeof(ValueSetsHeader) + sets * sizeof(ValueSetEntry), kVxlAlignment);
}
constexpr std::uint64_t value_array_stride(std::uint64_t count) { return align_up(count * 4, kVxlAlignment); }
// Payload size of `sets` arrays of `count` values (0 sets: no section).
constexpr std::uint64_t value_sets_bytes(std::uint64_t sets, std::uint64_t count) {
  return sets == 0 ? 0 : value_sets_data_offset(sets) + sets * value_array_stride(count);
}

// `name` as stored: NUL, '/' and '\' written as VTK escapes them (%00, %2F, %5C: a stored name ends at
// its NUL, and `export` makes TRX members dpv/NAME.float32), made valid UTF-8 (invalid bytes read as
// Latin-1), cut to kMaxValueSetName bytes at a character boundary.
std::string value_set_name(const std::string& name);

// The names one kind of value sets is written under, from the source's, each one that `verify` and
// `export` accept: value_set_name of each; "" as `fallback`, "." and ".." as %2E and %2E%2E; and unique (a
// name met before gets " (2)", " (3)", ...). Each name changed adds a warning to `warnings`.
std::vector<std::string> usable_value_set_names(std::span<const std::string> names, const std::string& fallback,
                                                std::vector<std::string>& warnings);

// Writing: lays out the header and names in `payload` (sized by value_sets_bytes, zero-filled) and
// returns the arrays for the caller to fill; then finish_value_sets records each array's min and max.
std::vector<std::span<float>> layout_value_sets(std::span<std::uint8_t> payload, std::span<const std::string> names,
                                                std::uint64_t count);
void finish_value_sets(std::span<std::uint8_t> payload);

// Reading a validated section (VxlFile::open checks the structure in O(sets)).
class ValueSets {
 public:
  ValueSets() = default;
  // Throws vxl::Error (Input) naming `path` and the byte offset (`at`: the payload's file offset) unless
  // `payload` has the layout above with value_count == `count` and every name is valid UTF-8.
  ValueSets(std::span<const std::uint8_t> payload, std::uint64_t count, const std::string& path, std::uint64_t at);

  std::uint32_t size() const { return static_cast<std::uint32_t>(entries_.size()); }
  bool empty() const { return entries_.empty(); }
  std::string name(std::uint32_t k) const;
  float min(std::uint32_t k) const { return entries_[k].min; }
  float max(std::uint32_t k) const { return entries_[k].max; }
  std::span<const float> values(std::uint32_t k) const;
  // The set called `name`, or -1.
  int find(const std::string& name) const;
  std::span<const std::uint8_t> payload() const { return payload_; }

 private:
  std::span<const std::uint8_t> payload_;
  std::span<const ValueSetEntry> entries_;
  std::uint64_t count_ = 0;
};

}  // namespace vxl
