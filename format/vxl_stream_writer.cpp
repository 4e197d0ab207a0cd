#include "format/vxl_stream_writer.h"

#include <cstring>
#include <stdexcept>

namespace vxl {

VxlStreamWriter::VxlStreamWriter(const std::string& path, const VxlSectionSizes& sizes)
    : out_(path), positions_(sizes.positions) {
  VxlLayout layout = plan_vxl_layout(sizes);
  table_ = std::move(layout.table);
  file_size_ = layout.file_size;
  written_.assign(table_.size(), 0);
  for (std::size_t i = 0; i < table_.size(); ++i) checksums_.push_back(std::make_unique<Xxh3_64Stream>());
  for (std::size_t s = 0; s < kCount; ++s) {
    entry_[s] = table_.size();
    for (std::size_t i = 0; i < table_.size(); ++i)
      if (std::memcmp(table_[i].id, kIds[s], 4) == 0) entry_[s] = i;
  }
  out_.allocate(file_size_);  // zeros everywhere: the padding between payloads is never written
}

void VxlStreamWriter::append(Section section, std::span<const std::uint8_t> bytes) {
  const std::size_t i = entry_[section];
  if (i >= table_.size() || bytes.size() > table_[i].size - written_[i])
    throw std::logic_error("VxlStreamWriter::append: more bytes than the section was planned for");
  if (bytes.empty()) return;
  out_.pwrite(bytes.data(), bytes.size(), table_[i].offset + written_[i]);
  checksums_[i]->update(bytes.data(), bytes.size());
  written_[i] += bytes.size();
}

AtomicOutputFile::Window VxlStreamWriter::open_window(Section section, std::uint64_t size, unsigned threads) {
  const std::size_t i = entry_[section];
  if (i >= table_.size() || size > table_[i].size - written_[i])
    throw std::logic_error("VxlStreamWriter::append_in_place: more bytes than the section was planned for");
  AtomicOutputFile::Window window = out_.map_window(table_[i].offset + written_[i], size);
  prefault_for_write(window.bytes(), threads);
  return window;
}

void VxlStreamWriter::close_window(Section section, AtomicOutputFile::Window& window) {
  const std::size_t i = entry_[section];
  const std::span<std::uint8_t> bytes = window.bytes();
  checksums_[i]->update(bytes.data(), bytes.size());
  written_[i] += bytes.size();
  window = AtomicOutputFile::Window();
}

void VxlStreamWriter::append_meta(const MetaSection& meta) {
  MetaSection m = meta;
  std::memset(m.reserved, 0, sizeof m.reserved);
  append(kMeta, {reinterpret_cast<const std::uint8_t*>(&m), sizeof m});
}

void VxlStreamWriter::commit() {
  for (std::size_t i = 0; i < table_.size(); ++i) {
    if (written_[i] != table_[i].size)
      throw std::logic_error("VxlStreamWriter::commit: section " + std::string(table_[i].id, 4) + " is incomplete");
    table_[i].checksum = checksums_[i]->digest();
  }
  std::vector<std::uint8_t> header = vxl_header_bytes(table_, file_size_, positions_);
  out_.pwrite(header.data(), header.size(), 0);
  out_.commit();
}

}  // namespace vxl
