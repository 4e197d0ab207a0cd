#include "format/vxlz_values.h"

#include <algorithm>
#include <cstring>

#include "format/base/error.h"
#include "format/base/parallel.h"
#include "format/base/utf8_check.h"
#include "format/vxl_value_sets.h"

namespace vxl {
namespace {

// §4.7: header, then one 64-byte entry per set, then the sets' zlib sections back to back.
struct ValueSectionHeader {
  std::uint32_t set_count;
  std::uint32_t reserved;
  std::uint64_t value_count;
};
struct ValueStreamEntry {
  char name[48];
  std::uint32_t coding;
  std::uint32_t reserved;
  std::uint64_t stream_size;
};
static_assert(sizeof(ValueSectionHeader) == 16 && sizeof(ValueStreamEntry) == 64);

std::vector<std::uint8_t> plain_bytes(std::span<const float> v) {
  std::vector<std::uint8_t> raw(4 * v.size());
  if (!v.empty()) std::memcpy(raw.data(), v.data(), raw.size());
  return raw;
}

// Byte k of every XOR difference, then byte k + 1: values of one set share sign, exponent and leading
// mantissa bits, so the high planes of the differences are mostly zero and deflate to little.
std::vector<std::uint8_t> xor_planes(std::span<const float> v) {
  const std::size_t n = v.size();
  std::vector<std::uint8_t> raw(4 * n);
  std::uint32_t previous = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t bits;
    std::memcpy(&bits, &v[i], 4);
    const std::uint32_t d = bits ^ previous;
    previous = bits;
    for (int k = 0; k < 4; ++k) raw[k * n + i] = static_cast<std::uint8_t>(d >> (8 * k));
  }
  return raw;
}

void undo_xor_planes(std::span<const std::uint8_t> raw, std::span<float> v) {
  const std::size_t n = v.size();
  std::uint32_t previous = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t d = 0;
    for (int k = 0; k < 4; ++k) d |= std::uint32_t(raw[k * n + i]) << (8 * k);
    previous ^= d;
    std::memcpy(&v[i], &previous, 4);
  }
}

}  // namespace

std::vector<std::uint8_t> encode_value_section(std::span<const NamedValues> sets, unsigned threads) {
  if (sets.empty() || sets.size() > kMaxValueSets)
    throw Error(ErrorKind::Unsupported, "", std::nullopt, "a package holds 1..64 value sets of a kind");
  const std::uint64_t n = sets[0].values.size();
  for (const NamedValues& s : sets)
    if (s.values.size() != n)
      throw Error(ErrorKind::Input, "", std::nullopt, "value sets of one kind differ in length");
  std::vector<std::vector<std::uint8_t>> streams(sets.size());
  std::vector<std::uint32_t> codings(sets.size());
  parallel_for(sets.size(), threads, [&](std::uint64_t k, unsigned) {
    std::vector<std::uint8_t> plain = deflate_section(plain_bytes(sets[k].values));
    std::vector<std::uint8_t> planes = deflate_section(xor_planes(sets[k].values));
    const bool use_planes = planes.size() < plain.size();
    codings[k] = use_planes ? kValueCodingXorPlanes : kValueCodingPlain;
    streams[k] = std::move(use_planes ? planes : plain);
  });
  std::vector<std::uint8_t> out(sizeof(ValueSectionHeader) + sets.size() * sizeof(ValueStreamEntry));
  const ValueSectionHeader h{static_cast<std::uint32_t>(sets.size()), 0, n};
  std::memcpy(out.data(), &h, sizeof h);
  for (std::size_t k = 0; k < sets.size(); ++k) {
    ValueStreamEntry e{};
    const std::string name = value_set_name(sets[k].name);
    std::memcpy(e.name, name.data(), name.size());
    e.coding = codings[k];
    e.stream_size = streams[k].size();
    std::memcpy(out.data() + sizeof h + k * sizeof e, &e, sizeof e);
  }
  for (const auto& s : streams) out.insert(out.end(), s.begin(), s.end());
  return out;
}

std::vector<NamedValues> decode_value_section(std::span<const std::uint8_t> payload, std::uint64_t count,
                                              const StreamContext& context, unsigned threads) {
  const std::string& p = context.file;
  const std::uint64_t at = context.section_offset;
  auto fail = [&](std::uint64_t offset, const std::string& what) {
    fail_input(p, at + offset, "section " + context.section + ": " + what);
  };
  ValueSectionHeader h;
  if (payload.size() < sizeof h) fail(0, "shorter than its 16-byte header");
  std::memcpy(&h, payload.data(), sizeof h);
  if (h.set_count < 1 || h.set_count > kMaxValueSets) fail(0, "set count must be 1..64");
  if (h.reserved != 0) fail(4, "reserved bytes are not zero");
  if (h.value_count != count)
    fail(8, "holds " + std::to_string(h.value_count) + " values per set, expected " + std::to_string(count));
  const std::uint64_t streams_at = sizeof h + std::uint64_t(h.set_count) * sizeof(ValueStreamEntry);
  if (payload.size() < streams_at) fail(0, "too short for its " + std::to_string(h.set_count) + " set entries");
  // count <= 2^64 / 4 is implied by the check below: a raw size must equal 4 * count exactly.
  if (count > (~std::uint64_t(0) >> 3)) fail(8, "value count too large");
  std::vector<ValueStreamEntry> entries(h.set_count);
  std::vector<std::uint64_t> stream_at(h.set_count);
  std::uint64_t position = streams_at;
  for (std::uint32_t k = 0; k < h.set_count; ++k) {
    ValueStreamEntry& e = entries[k];
    const std::uint64_t entry_at = sizeof h + k * sizeof e;
    std::memcpy(&e, payload.data() + entry_at, sizeof e);
    const char* nul = static_cast<const char*>(std::memchr(e.name, 0, sizeof e.name));
    if (!nul) fail(entry_at, "set name is not NUL-terminated");
    if (std::any_of(nul, static_cast<const char*>(e.name) + sizeof e.name, [](char c) { return c != 0; }))
      fail(entry_at, "set name padding is not zero");
    // The .vxl requires UTF-8 names (its spec §7): a package that does not have them is refused here, not
    // unpacked into a file that `open` refuses.
    if (!is_valid_utf8(std::string_view(e.name, nul - e.name))) fail(entry_at, "set name is not valid UTF-8");
    if (e.coding > kValueCodingXorPlanes)
      throw Error(
          ErrorKind::Unsupported, p, at + entry_at + 48,
          "section " + context.section + ": value coding " + std::to_string(e.coding) + " (this reader knows 0 and 1)");
    if (e.reserved != 0) fail(entry_at + 52, "reserved bytes are not zero");
    if (e.stream_size < 8 || e.stream_size > payload.size() - position)
      fail(entry_at + 56, "set stream runs past the end of the section");
    std::uint64_t raw_size;
    std::memcpy(&raw_size, payload.data() + position, 8);
    if (raw_size != 4 * count)
      fail(position,
           "set stream inflates to " + std::to_string(raw_size) + " bytes, expected " + std::to_string(4 * count));
    stream_at[k] = position;
    position += e.stream_size;
  }
  if (position != payload.size()) fail(position, "bytes after the last set stream");

  std::vector<NamedValues> sets(h.set_count);
  parallel_for(h.set_count, threads, [&](std::uint64_t k, unsigned) {
    StreamContext c = context;
    c.section_offset = at + stream_at[k];
    const std::vector<std::uint8_t> raw = inflate_section(payload.subspan(stream_at[k], entries[k].stream_size), c);
    NamedValues& s = sets[k];
    s.name = entries[k].name;
    s.values.resize(count);
    if (entries[k].coding == kValueCodingPlain) {
      if (count > 0) std::memcpy(s.values.data(), raw.data(), raw.size());
    } else {
      undo_xor_planes(raw, s.values);
    }
  });
  return sets;
}

}  // namespace vxl
