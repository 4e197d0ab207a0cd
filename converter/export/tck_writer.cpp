#include "converter/export/tck_writer.h"

#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "converter/readers/mrtrix_header.h"

namespace vxl {

namespace {

std::string mrtrix_header(const std::string& magic, std::uint64_t count, const std::vector<std::string>& extra_header) {
  std::string head = magic + "\ndatatype: Float32LE\ncount: " + std::to_string(count) + "\n";
  for (const std::string& line : extra_header) head += line + "\n";
  // "file: . OFFSET" states the header's own length: pad the number to a fixed width so that the
  // length is known before the number is written.
  head += "file: . ";
  const std::size_t width = 20;
  const std::string tail = "\nEND\n";
  std::string offset = std::to_string(head.size() + width + tail.size());
  head += std::string(width - offset.size(), ' ') + offset + tail;
  return head;
}

// Bytes staged per direct write: large enough that the writes are few, small beside the output; the queue's
// spares let the writes fall this many stagings behind.
constexpr std::uint64_t kDirectStagingBytes = 4ull << 20;
constexpr std::uint64_t kSpareStagings = 2;

}  // namespace

MrtrixTrackWriter::MrtrixTrackWriter(const std::string& path, const char* magic, std::size_t record_values,
                                     std::uint64_t count, const std::vector<std::string>& extra_header,
                                     std::optional<std::uint64_t> records)
    : out_(path), record_values_(record_values) {
  const std::string head = mrtrix_header(magic, count, extra_header);
  if (!records) {
    buffer_.reserve(1 << 20);
    out_.write(head.data(), head.size());
    return;
  }
  // Every record, a separator after each streamline and the terminator, 4 bytes a value.
  const std::uint64_t size = head.size() + (*records + count + 1) * record_values * sizeof(float);
  out_.allocate(size);
  void* memory = std::aligned_alloc(DirectRegionWriter::kBlock, (1 + kSpareStagings) * kDirectStagingBytes);
  if (memory == nullptr) throw std::bad_alloc();
  stagings_ = {static_cast<std::uint8_t*>(memory), std::free};
  std::vector<std::uint8_t*> spares;
  for (std::uint64_t k = 1; k <= kSpareStagings; ++k) spares.push_back(stagings_.get() + k * kDirectStagingBytes);
  const int direct_fd = out_.direct_descriptor();
  queue_ = std::make_unique<DirectWriteQueue>(out_, direct_fd, spares, kDirectStagingBytes);
  direct_ = std::make_unique<DirectRegionWriter>(out_, direct_fd, 0, size, kDirectStagingBytes, stagings_.get(),
                                                 queue_.get());
  direct_->append({reinterpret_cast<const std::uint8_t*>(head.data()), head.size()});
}

void MrtrixTrackWriter::add(std::span<const float> values) {
  if (direct_) {
    // Straight into the direct writer's staging: one copy of each streamline instead of two.
    static constexpr float kSeparator[3] = {std::numeric_limits<float>::quiet_NaN(),
                                            std::numeric_limits<float>::quiet_NaN(),
                                            std::numeric_limits<float>::quiet_NaN()};
    direct_->append({reinterpret_cast<const std::uint8_t*>(values.data()), values.size_bytes()});
    direct_->append({reinterpret_cast<const std::uint8_t*>(kSeparator), record_values_ * sizeof(float)});
    return;
  }
  buffer_.insert(buffer_.end(), values.begin(), values.end());
  buffer_.insert(buffer_.end(), record_values_, std::numeric_limits<float>::quiet_NaN());
  if (buffer_.size() >= (1 << 20)) flush();
}

void MrtrixTrackWriter::flush() {
  if (direct_)
    direct_->append({reinterpret_cast<const std::uint8_t*>(buffer_.data()), buffer_.size() * sizeof(float)});
  else
    out_.write(buffer_.data(), buffer_.size() * sizeof(float));
  buffer_.clear();
}

void MrtrixTrackWriter::finish() {
  buffer_.insert(buffer_.end(), record_values_, std::numeric_limits<float>::infinity());
  flush();
  if (direct_ && !direct_->complete())
    throw std::logic_error("MrtrixTrackWriter: fewer records than the writer was told of");
  if (queue_) queue_->finish();
  out_.commit();
}

TckWriter::TckWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header,
                     std::optional<std::uint64_t> points)
    : MrtrixTrackWriter(path, kTckFile.magic, 3, count, extra_header, points) {}

TsfWriter::TsfWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header,
                     std::optional<std::uint64_t> points)
    : MrtrixTrackWriter(path, kTsfFile.magic, 1, count, extra_header, points) {}

}  // namespace vxl
