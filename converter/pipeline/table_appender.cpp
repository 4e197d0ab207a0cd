#include "converter/pipeline/table_appender.h"

#include <utility>

namespace vxl::streaming {

TableAppender::TableAppender(VxlStreamWriter& out, std::size_t entries) : out_(out), entries_(entries) {
  for (Buffers* b : {&filling_, &writing_}) {
    b->voxlines.reserve(entries);
    b->streamlines.reserve(entries);
  }
}

void TableAppender::append(const Buffers& b) {
  out_.append_items<std::uint64_t>(VxlStreamWriter::kStrm, b.streamlines);
  out_.append_items<VoxlineEntry>(VxlStreamWriter::kVxln, b.voxlines);
}

void TableAppender::write_filled() {
  if (write_.valid()) write_.get();
  std::swap(filling_, writing_);
  filling_.voxlines.clear();
  filling_.streamlines.clear();
  write_ = BackgroundTask<>([this] { append(writing_); });
}

void TableAppender::finish() {
  if (write_.valid()) write_.get();
  append(filling_);
  filling_.voxlines.clear();
  filling_.streamlines.clear();
}

}  // namespace vxl::streaming
