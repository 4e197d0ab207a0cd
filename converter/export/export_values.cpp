#include "converter/export/export_values.h"

#include <charconv>

#include "format/base/error.h"
#include "format/vxl_streamlines.h"

namespace vxl {
namespace {

// "base[i]" -> base and i; nothing for other names.
bool split_component(const std::string& name, std::string& base, std::uint32_t& index) {
  const std::size_t open = name.rfind('[');
  if (open == std::string::npos || open == 0 || name.back() != ']' || open + 2 >= name.size()) return false;
  const char* first = name.data() + open + 1;
  const char* last = name.data() + name.size() - 1;
  if (*first == '0' && last - first > 1) return false;  // no leading zeros: "x[01]" is a name of its own
  const auto [end, ec] = std::from_chars(first, last, index);
  if (ec != std::errc() || end != last) return false;
  base = name.substr(0, open);
  return true;
}

// Members for one kind: `count` values per set; `dir` is "dpv" or "dps".
void add_members(const VxlFile& file, const ValueSets& sets, const std::string& dir, std::uint64_t count,
                 const std::vector<std::uint64_t>* vertices, const StreamlineSubset* subset,
                 std::vector<TrxValueMember>& out) {
  auto column = [&](std::uint32_t k) {
    if (vertices) return values_at(file, k, *vertices);
    if (subset) return subset->pick(sets.values(k));
    return std::vector<float>(sets.values(k).begin(), sets.values(k).end());
  };
  for (const ValueSetRun& run : value_set_runs(sets)) {
    const std::string& base = run.name;
    const std::uint32_t k = run.first, m = run.components;
    if (!usable_trx_member_name(base, dir + "/", (m > 1 ? "." + std::to_string(m) : std::string()) + ".float32"))
      fail_unsupported(file.path(),
                       "value set name '" + base + "' cannot be a TRX member name (" + dir + "/NAME.float32)");
    TrxValueMember member;
    member.name = dir + "/" + base + (m > 1 ? "." + std::to_string(m) : "") + ".float32";
    member.data.resize(count * m);
    for (std::uint32_t c = 0; c < m; ++c) {
      const std::vector<float> v = column(k + c);
      for (std::uint64_t i = 0; i < count; ++i) member.data[i * m + c] = v[i];
    }
    out.push_back(std::move(member));
  }
}

}  // namespace

bool usable_trx_member_name(const std::string& name, const std::string& folder, const std::string& suffix) {
  return !name.empty() && name != "." && name != ".." &&
         name.find_first_of(std::string("/\\\0", 3)) == std::string::npos &&
         name.size() <= 0xFFFF - folder.size() - suffix.size();
}

std::vector<ValueSetRun> value_set_runs(const ValueSets& sets) {
  std::vector<ValueSetRun> runs;
  for (std::uint32_t k = 0; k < sets.size();) {
    std::string base, next_base;
    std::uint32_t index = 0, m = 1;
    if (split_component(sets.name(k), base, index) && index == 0) {
      // The longest run base[0], base[1], … that follows.
      while (k + m < sets.size() && split_component(sets.name(k + m), next_base, index) && next_base == base &&
             index == m)
        ++m;
      if (m == 1) base = sets.name(k);  // a lone base[0] stays as it is named
    } else {
      base = sets.name(k);
    }
    runs.push_back({base, k, m});
    k += m;
  }
  return runs;
}

std::vector<std::uint64_t> source_vertex_indices(const VxlFile& file, const StreamlineSubset* subset) {
  std::vector<std::uint64_t> out;
  out.reserve(subset_counts(file, subset).points);
  WalkCallbacks cb;
  cb.threads = 0;  // the points decoded on every core
  cb.read_points = [&](std::uint64_t s) { return in_subset(subset, s); };
  cb.voxline = [&](const VoxlineVisit& v) {
    if (!in_subset(subset, v.streamline)) return;
    for (std::uint32_t i = v.synthetic_first ? 1 : 0; i < v.own_points; ++i) out.push_back(v.first_vertex + i);
  };
  walk_streamlines(file, cb);
  return out;
}

std::vector<float> values_at(const VxlFile& file, std::uint32_t set, const std::vector<std::uint64_t>& vertices) {
  const std::span<const float> v = file.vertex_values().values(set);
  std::vector<float> out(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) out[i] = v[vertices[i]];
  return out;
}

std::vector<TrxValueMember> trx_value_members(const VxlFile& file, const StreamlineSubset* subset) {
  std::vector<TrxValueMember> out;
  if (!file.vertex_values().empty()) {
    const std::vector<std::uint64_t> vertices = source_vertex_indices(file, subset);
    add_members(file, file.vertex_values(), "dpv", vertices.size(), &vertices, nullptr, out);
  }
  add_members(file, file.streamline_values(), "dps", subset ? subset->size() : file.meta().streamline_count, nullptr,
              subset, out);
  return out;
}

}  // namespace vxl
