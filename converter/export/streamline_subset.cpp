#include "converter/export/streamline_subset.h"

#include <algorithm>
#include <cassert>

#include "format/base/error.h"
#include "format/base/parallel.h"

namespace vxl {

StreamlineSubset group_subset(const VxlFile& file, const std::string& name) {
  std::vector<StreamlineGroup> groups = file.groups();
  for (StreamlineGroup& g : groups)
    if (g.name == name) return StreamlineSubset(file.meta().streamline_count, std::move(g.members));
  std::string names;
  for (std::size_t i = 0; i < groups.size(); ++i) names += (i ? ", '" : "'") + groups[i].name + "'";
  throw Error(ErrorKind::Usage, file.path(), std::nullopt,
              "has no group '" + name + "'" +
                  (groups.empty() ? std::string(" (it has no groups)") : " (it has " + names + ")"));
}

StreamlineSubset::StreamlineSubset(std::uint64_t total, std::vector<std::uint64_t> indices)
    : indices_(std::move(indices)), member_(total, false) {
  for (std::size_t i = 0; i < indices_.size(); ++i) {
    assert(indices_[i] < total && (i == 0 || indices_[i - 1] < indices_[i]) && "subset indices out of order");
    member_[indices_[i]] = true;
  }
}

std::vector<std::uint64_t> StreamlineSubset::renumber(std::span<const std::uint64_t> members) const {
  std::vector<std::uint64_t> out;
  auto from = indices_.begin();
  for (std::uint64_t s : members) {
    if (s >= member_.size() || !member_[s]) continue;
    from = std::lower_bound(from, indices_.end(), s);
    out.push_back(static_cast<std::uint64_t>(from - indices_.begin()));
  }
  return out;
}

std::vector<float> StreamlineSubset::pick(std::span<const float> per_streamline) const {
  std::vector<float> out(indices_.size());
  for (std::size_t i = 0; i < indices_.size(); ++i) out[i] = per_streamline[indices_[i]];
  return out;
}

SubsetCounts subset_counts(const VxlFile& file, const StreamlineSubset* subset) {
  if (!subset) return {file.meta().streamline_count, file.meta().point_count};
  const auto strm = file.streamline_first_voxline();
  const auto voxlines = file.voxlines();
  // In chunks on every core (a gather through the voxline table, waiting on memory); the first fault in
  // streamline order is the one reported.
  const std::span<const std::uint64_t> indices = subset->indices();
  constexpr std::uint64_t kChunk = 1 << 14;
  std::vector<std::uint64_t> points((indices.size() + kChunk - 1) / kChunk);
  parallel_for_first_error_in_order(points.size(), 0, [&](std::uint64_t chunk, unsigned) {
    std::uint64_t sum = 0;
    for (const std::uint64_t s : indices.subspan(chunk * kChunk, std::min(kChunk, indices.size() - chunk * kChunk))) {
      file.check_streamline_run(s);
      for (std::uint64_t j = strm[s]; j < strm[s + 1]; ++j) {
        const std::uint32_t own = voxlines[j].count_flags & kVoxlineCountMask;
        const std::uint32_t skip = (voxlines[j].count_flags & kVoxlineSyntheticFirst) ? 1 : 0;
        file.check_voxline(j);
        sum += own - skip;
      }
    }
    points[chunk] = sum;
  });
  SubsetCounts c{subset->size(), 0};
  for (const std::uint64_t p : points) c.points += p;
  return c;
}

}  // namespace vxl
