// Some of a .vxl's streamlines, by their index in the source (what `voxlines select` keeps). The exporters
// take one and write only those streamlines, renumbered 0, 1, … in source order, with their values and
// their group memberships.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "format/vxl_file.h"

namespace vxl {

class StreamlineSubset {
 public:
  // `indices` strictly increasing, each below `total` (asserted: a caller's contract, not data).
  StreamlineSubset(std::uint64_t total, std::vector<std::uint64_t> indices);

  bool contains(std::uint64_t streamline) const { return member_[streamline]; }
  std::uint64_t size() const { return indices_.size(); }
  std::span<const std::uint64_t> indices() const { return indices_; }
  // The members (strictly increasing source indices) that are in the subset, as subset indices.
  std::vector<std::uint64_t> renumber(std::span<const std::uint64_t> members) const;
  // One value per source streamline -> one per subset streamline.
  std::vector<float> pick(std::span<const float> per_streamline) const;

 private:
  std::vector<std::uint64_t> indices_;
  std::vector<bool> member_;
};

// The streamlines of group `name`. Throws vxl::Error (Usage) when the file has no such group, naming those
// it has.
StreamlineSubset group_subset(const VxlFile& file, const std::string& name);

// Whether `streamline` is written: every one when there is no subset.
inline bool in_subset(const StreamlineSubset* subset, std::uint64_t streamline) {
  return !subset || subset->contains(streamline);
}

// Streamlines and source points (synthetic face points excluded) of the subset, or of the file without
// one: from the streamline and voxline tables alone, no vertex read. Throws vxl::Error (Input) on a
// voxline table that does not hold together.
struct SubsetCounts {
  std::uint64_t streamlines = 0, points = 0;
};
SubsetCounts subset_counts(const VxlFile& file, const StreamlineSubset* subset);

}  // namespace vxl
