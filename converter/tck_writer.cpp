#include "converter/tck_writer.h"

#include <limits>

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

TckWriter::TckWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header)
    : out_(path) {
  const std::string head = mrtrix_header("mrtrix tracks", count, extra_header);
  out_.write(head.data(), head.size());
  buffer_.reserve(1 << 20);
}

void TckWriter::add(std::span<const float> xyz) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  buffer_.insert(buffer_.end(), xyz.begin(), xyz.end());
  buffer_.insert(buffer_.end(), {nan, nan, nan});
  if (buffer_.size() >= (1 << 20)) flush();
}

void TckWriter::flush() {
  out_.write(buffer_.data(), buffer_.size() * sizeof(float));
  buffer_.clear();
}

void TckWriter::finish() {
  const float inf = std::numeric_limits<float>::infinity();
  buffer_.insert(buffer_.end(), {inf, inf, inf});
  flush();
  out_.commit();
}

TsfWriter::TsfWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header)
    : out_(path) {
  const std::string head = mrtrix_header("mrtrix track scalars", count, extra_header);
  out_.write(head.data(), head.size());
  buffer_.reserve(1 << 20);
}

void TsfWriter::add(std::span<const float> values) {
  buffer_.insert(buffer_.end(), values.begin(), values.end());
  buffer_.push_back(std::numeric_limits<float>::quiet_NaN());
  if (buffer_.size() >= (1 << 20)) flush();
}

void TsfWriter::flush() {
  out_.write(buffer_.data(), buffer_.size() * sizeof(float));
  buffer_.clear();
}

void TsfWriter::finish() {
  buffer_.push_back(std::numeric_limits<float>::infinity());
  flush();
  out_.commit();
}

}  // namespace vxl
