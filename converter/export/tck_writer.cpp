#include "converter/export/tck_writer.h"

#include <limits>

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

}  // namespace

MrtrixTrackWriter::MrtrixTrackWriter(const std::string& path, const char* magic, std::size_t record_values,
                                     std::uint64_t count, const std::vector<std::string>& extra_header)
    : out_(path), record_values_(record_values) {
  const std::string head = mrtrix_header(magic, count, extra_header);
  out_.write(head.data(), head.size());
  buffer_.reserve(1 << 20);
}

void MrtrixTrackWriter::add(std::span<const float> values) {
  buffer_.insert(buffer_.end(), values.begin(), values.end());
  buffer_.insert(buffer_.end(), record_values_, std::numeric_limits<float>::quiet_NaN());
  if (buffer_.size() >= (1 << 20)) flush();
}

void MrtrixTrackWriter::flush() {
  out_.write(buffer_.data(), buffer_.size() * sizeof(float));
  buffer_.clear();
}

void MrtrixTrackWriter::finish() {
  buffer_.insert(buffer_.end(), record_values_, std::numeric_limits<float>::infinity());
  flush();
  out_.commit();
}

TckWriter::TckWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header)
    : MrtrixTrackWriter(path, kTckFile.magic, 3, count, extra_header) {}

TsfWriter::TsfWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header)
    : MrtrixTrackWriter(path, kTsfFile.magic, 1, count, extra_header) {}

}  // namespace vxl
