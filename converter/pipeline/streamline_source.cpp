#include "converter/pipeline/streamline_source.h"

#include <algorithm>

namespace vxl {

bool TractogramBatchSource::next(Tractogram& batch) {
  const std::vector<std::uint64_t>& offsets = tractogram_.offsets;
  const std::uint64_t first = next_, n = tractogram_.streamline_count();
  std::uint64_t end = first;
  while (end < n && (offsets[end] - offsets[first]) + (end - first) < batch_points_) ++end;
  batch.offsets.clear();
  batch.positions.clear();
  if (first >= end) {
    batch.offsets.push_back(0);
    return false;
  }
  for (std::uint64_t k = first; k <= end; ++k) batch.offsets.push_back(offsets[k] - offsets[first]);
  batch.positions.assign(tractogram_.positions.begin() + std::ptrdiff_t(3 * offsets[first]),
                         tractogram_.positions.begin() + std::ptrdiff_t(3 * offsets[end]));
  next_ = end;
  return true;
}

}  // namespace vxl
