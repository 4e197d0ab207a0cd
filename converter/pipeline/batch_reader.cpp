#include "converter/pipeline/batch_reader.h"

#include <algorithm>

namespace vxl {

BatchReader::BatchReader(const std::string& path, MemoryBudget& budget, unsigned threads, ProgressFn progress)
    : budget_(budget),
      plan_(plan_reading(budget)),
      threads_(std::max(1u, threads)),
      read_ahead_(threads > 1),
      progress_(std::move(progress)) {
  source_ = std::make_unique<TckBatchSource>(path, plan_);
}

BatchReader::BatchReader(std::unique_ptr<StreamlineSource> source, const ReadPlan& plan, MemoryBudget& budget,
                         unsigned threads, ProgressFn progress)
    : budget_(budget),
      plan_(plan),
      source_(std::move(source)),
      threads_(std::max(1u, threads)),
      read_ahead_(threads > 1),
      progress_(std::move(progress)) {}

void BatchReader::note_longest(const Tractogram& b, std::uint64_t first) {
  for (std::uint64_t k = 0; k < b.streamline_count(); ++k)
    if (b.offsets[k + 1] - b.offsets[k] > longest_) {
      longest_ = b.offsets[k + 1] - b.offsets[k];
      longest_index_ = first + k;
    }
}

void BatchReader::check_overflow(const Tractogram& b, std::uint64_t first) const {
  if (source_->overflowed())
    budget_.fail(b.point_count() * kHeldBytesPerPoint, budget_.used() - held_,
                 "streamline " + std::to_string(first + b.streamline_count()) + ", of more than " +
                     std::to_string(b.point_count() - b.offsets.back()) + " points, held whole while reading,");
}

void BatchReader::track_batches() {
  // Both batches keep their largest size; pass 1 finds it (later passes cut the same batches).
  const std::uint64_t bytes = (batches_[0].positions.capacity() + batches_[1].positions.capacity()) * sizeof(float) +
                              (batches_[0].offsets.capacity() + batches_[1].offsets.capacity()) * sizeof(std::uint64_t);
  budget_.track(bytes, held_, [&] {
    return "reading two batches of streamlines, one holding streamline " + std::to_string(longest_index_) + " (" +
           std::to_string(longest_) + " points) whole,";
  });
}

}  // namespace vxl
