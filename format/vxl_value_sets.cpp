#include "format/vxl_value_sets.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

#include "format/base/error.h"
#include "format/base/utf8_check.h"

namespace vxl {

namespace {

// `name` cut to at most `bytes` bytes at a character boundary.
std::string cut_to(std::string name, std::size_t bytes) {
  if (name.size() <= bytes) return name;
  std::size_t n = bytes;
  while (n > 0 && (static_cast<unsigned char>(name[n]) & 0xC0) == 0x80) --n;  // not inside a character
  return name.substr(0, n);
}

}  // namespace

std::string value_set_name(const std::string& raw) {
  std::string escaped;
  for (char c : raw) escaped += c == '\0' ? "%00" : c == '/' ? "%2F" : c == '\\' ? "%5C" : std::string(1, c);
  // Readers refuse a name that is not UTF-8 (VxlFile::open), so one from a non-UTF-8 file name is converted.
  return cut_to(to_valid_utf8(escaped), kMaxValueSetName);
}

std::vector<std::string> usable_value_set_names(std::span<const std::string> names, const std::string& fallback,
                                                std::vector<std::string>& warnings) {
  std::vector<std::string> out;
  std::set<std::string> used;
  for (const std::string& raw : names) {
    std::string name = value_set_name(raw);
    if (name.empty()) name = fallback;
    if (name == ".") name = "%2E";
    if (name == "..") name = "%2E%2E";
    const std::string base = name;
    for (int k = 2; used.count(name); ++k) {
      const std::string suffix = " (" + std::to_string(k) + ")";
      name = cut_to(base, kMaxValueSetName - suffix.size()) + suffix;
    }
    if (name != raw) {
      std::string shown;
      for (char c : raw) shown += c == '\0' ? std::string("\\0") : std::string(1, c);
      warnings.push_back("value set '" + to_valid_utf8(shown) + "' written as '" + name + "'");
    }
    used.insert(name);
    out.push_back(std::move(name));
  }
  return out;
}

std::vector<std::span<float>> layout_value_sets(std::span<std::uint8_t> payload, std::span<const std::string> names,
                                                std::uint64_t count) {
  std::vector<std::span<float>> arrays;
  if (names.empty()) return arrays;
  ValueSetsHeader h{static_cast<std::uint32_t>(names.size()), 0, count};
  std::memcpy(payload.data(), &h, sizeof h);
  for (std::size_t k = 0; k < names.size(); ++k) {
    ValueSetEntry e{};
    const std::string name = value_set_name(names[k]);
    std::memcpy(e.name, name.data(), name.size());
    std::memcpy(payload.data() + sizeof h + k * sizeof e, &e, sizeof e);
    std::uint8_t* data = payload.data() + value_sets_data_offset(names.size()) + k * value_array_stride(count);
    arrays.emplace_back(reinterpret_cast<float*>(data), count);  // 64-byte aligned in the mapping
  }
  return arrays;
}

void finish_value_sets(std::span<std::uint8_t> payload) {
  if (payload.empty()) return;
  ValueSetsHeader h;
  std::memcpy(&h, payload.data(), sizeof h);
  for (std::uint32_t k = 0; k < h.set_count; ++k) {
    const float* v = reinterpret_cast<const float*>(payload.data() + value_sets_data_offset(h.set_count) +
                                                    k * value_array_stride(h.value_count));
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (std::uint64_t i = 0; i < h.value_count; ++i)
      if (std::isfinite(v[i])) {
        lo = std::min(lo, v[i]);
        hi = std::max(hi, v[i]);
      }
    if (lo > hi) lo = hi = std::numeric_limits<float>::quiet_NaN();
    std::uint8_t* entry = payload.data() + sizeof h + k * sizeof(ValueSetEntry);
    std::memcpy(entry + offsetof(ValueSetEntry, min), &lo, 4);
    std::memcpy(entry + offsetof(ValueSetEntry, max), &hi, 4);
  }
}

ValueSets::ValueSets(std::span<const std::uint8_t> payload, std::uint64_t count, const std::string& path,
                     std::uint64_t at)
    : payload_(payload), count_(count) {
  if (payload.size() < sizeof(ValueSetsHeader))
    fail_input(path, at, "value-set section shorter than its 16-byte header");
  ValueSetsHeader h;
  std::memcpy(&h, payload.data(), sizeof h);
  if (h.set_count < 1 || h.set_count > kMaxValueSets) fail_input(path, at, "value-set count must be 1..64");
  if (h.value_count != count)
    fail_input(path, at + 8,
               "value-set section holds " + std::to_string(h.value_count) + " values per set, expected " +
                   std::to_string(count));
  // count is a META count whose sections were already checked, so this cannot overflow.
  if (payload.size() != value_sets_bytes(h.set_count, count))
    fail_input(path, at,
               "value-set section size " + std::to_string(payload.size()) + " does not match " +
                   std::to_string(h.set_count) + " sets of " + std::to_string(count) + " values");
  entries_ = {reinterpret_cast<const ValueSetEntry*>(payload.data() + sizeof h), h.set_count};
  for (std::uint32_t k = 0; k < h.set_count; ++k) {
    const std::uint64_t entry_at = at + sizeof h + k * sizeof(ValueSetEntry);
    if (std::memchr(entries_[k].name, 0, sizeof entries_[k].name) == nullptr)
      fail_input(path, entry_at, "value-set name is not NUL-terminated");
    if (!is_valid_utf8(entries_[k].name)) fail_input(path, entry_at, "value-set name is not valid UTF-8");
  }
}

std::string ValueSets::name(std::uint32_t k) const { return entries_[k].name; }

std::span<const float> ValueSets::values(std::uint32_t k) const {
  const std::uint8_t* data = payload_.data() + value_sets_data_offset(entries_.size()) + k * value_array_stride(count_);
  return {reinterpret_cast<const float*>(data), static_cast<std::size_t>(count_)};
}

int ValueSets::find(const std::string& name) const {
  for (std::uint32_t k = 0; k < entries_.size(); ++k)
    if (this->name(k) == name) return static_cast<int>(k);
  return -1;
}

}  // namespace vxl
