#include "format/vxl_stream_writer.h"

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "format/base/error.h"
#include "format/voxel_voxlines.h"

namespace vxl {

VxlStreamWriter::VxlStreamWriter(const std::string& path, const VxlSectionSizes& sizes,
                                 std::uint64_t direct_staging_bytes)
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
  direct_fd_ = direct_staging_bytes > 0 ? out_.direct_descriptor() : -1;
  if (direct_fd_ >= 0)
    for (const SectionEntry& e : table_)
      regions_.push_back(
          std::make_unique<DirectRegionWriter>(out_, direct_fd_, e.offset, e.size, direct_staging_bytes));
}

std::unique_ptr<DirectRegionWriter> VxlStreamWriter::region_writer(Section section, std::uint64_t offset,
                                                                   std::uint64_t size, std::uint64_t staging_bytes,
                                                                   std::uint8_t* staging_memory,
                                                                   DirectWriteQueue* queue) {
  const std::size_t i = entry_[section];
  if (i >= table_.size() || offset > table_[i].size || size > table_[i].size - offset)
    throw std::logic_error("VxlStreamWriter::region_writer: a region outside the section");
  return std::make_unique<DirectRegionWriter>(out_, direct_fd_, table_[i].offset + offset, size, staging_bytes,
                                              staging_memory, queue);
}

std::unique_ptr<DirectWriteQueue> VxlStreamWriter::write_queue(std::vector<std::uint8_t*> spares,
                                                               std::uint64_t buffer_bytes) {
  return std::make_unique<DirectWriteQueue>(out_, direct_fd_, std::move(spares), buffer_bytes);
}

std::uint64_t VxlStreamWriter::read_back_bytes(std::uint64_t size) {
  constexpr std::uint64_t block = DirectRegionWriter::kBlock;
  return (size + block - 1) / block * block + block;  // a misaligned start adds a block
}

std::span<const std::uint8_t> VxlStreamWriter::read_back(Section section, std::uint64_t size,
                                                         std::span<std::uint8_t> buffer) {
  const std::size_t i = entry_[section];
  if (i >= table_.size() || size > table_[i].size - written_[i])
    throw std::logic_error("VxlStreamWriter::read_back: more bytes than the section holds");
  constexpr std::uint64_t block = DirectRegionWriter::kBlock;
  const std::uint64_t from = table_[i].offset + written_[i];
  // Direct reads take whole blocks into a block-aligned buffer: the blocks around [from, from + size).
  const std::uint64_t lo = from / block * block, hi = (from + size + block - 1) / block * block;
  if (buffer.size() < hi - lo || reinterpret_cast<std::uintptr_t>(buffer.data()) % block != 0)
    throw std::logic_error("VxlStreamWriter::read_back: the buffer is not block-aligned or too small");
  std::uint8_t* const data = buffer.data() + (from - lo);
  std::uint64_t done = 0;  // bytes of [lo, hi) read directly
  while (direct_fd_ >= 0 && lo + done < from + size) {
    const ssize_t n = ::pread(direct_fd_, buffer.data() + done, hi - lo - done, static_cast<off_t>(lo + done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EINVAL) break;  // no direct reads here: through the page cache
    if (n < 0)
      throw Error(ErrorKind::Output, out_.path(), std::nullopt,
                  std::string("read-back failed: ") + std::strerror(errno));
    if (n == 0) break;  // the file's end, inside the last block: read the rest plainly
    done += static_cast<std::uint64_t>(n);
  }
  if (lo + done < from + size) {
    const std::uint64_t start = std::max(from, lo + done);
    out_.pread(buffer.data() + (start - lo), from + size - start, start);
  }
  const std::span<const std::uint8_t> bytes(data, size);
  checksums_[i]->update(bytes.data(), bytes.size());
  written_[i] += size;
  return bytes;
}

void VxlStreamWriter::append(Section section, std::span<const std::uint8_t> bytes) {
  const std::size_t i = entry_[section];
  if (i >= table_.size() || bytes.size() > table_[i].size - written_[i])
    throw std::logic_error("VxlStreamWriter::append: more bytes than the section was planned for");
  if (bytes.empty()) return;
  if (regions_.empty())
    out_.pwrite(bytes.data(), bytes.size(), table_[i].offset + written_[i]);
  else
    regions_[i]->append(bytes);
  checksums_[i]->update(bytes.data(), bytes.size());
  written_[i] += bytes.size();
}

std::uint64_t VxlStreamWriter::block_lead(Section section, std::uint64_t at) const {
  const std::size_t i = entry_[section];
  if (i >= table_.size()) throw std::logic_error("VxlStreamWriter::block_lead: no such section");
  return (table_[i].offset + at) % DirectRegionWriter::kBlock;
}

void VxlStreamWriter::append_from_block(Section section, std::uint8_t* block, std::uint64_t size) {
  const std::size_t i = entry_[section];
  if (i >= table_.size() || size > table_[i].size - written_[i])
    throw std::logic_error("VxlStreamWriter::append_from_block: more bytes than the section was planned for");
  std::uint8_t* const bytes = block + block_lead(section, written_[i]);
  if (size == 0) return;
  checksums_[i]->update(bytes, size);  // first: the region may overwrite what precedes them, never them
  if (regions_.empty())
    out_.pwrite(bytes, size, table_[i].offset + written_[i]);
  else
    regions_[i]->append_from_block(block, size);
  written_[i] += size;
}

FileWindow VxlStreamWriter::open_window(Section section, std::uint64_t size, unsigned threads) {
  const std::size_t i = entry_[section];
  if (i >= table_.size() || size > table_[i].size - written_[i])
    throw std::logic_error("VxlStreamWriter::append_in_place: more bytes than the section was planned for");
  FileWindow window = out_.map_window(table_[i].offset + written_[i], size);
  prefault_for_write(window.bytes(), threads);
  return window;
}

void VxlStreamWriter::close_window(Section section, FileWindow& window) {
  const std::size_t i = entry_[section];
  const std::span<std::uint8_t> bytes = window.bytes();
  checksums_[i]->update(bytes.data(), bytes.size());
  window.write_back();
  written_[i] += bytes.size();
  window = FileWindow();
}

std::span<std::uint8_t> VxlStreamWriter::fill_buffer(Section section, std::uint64_t size, unsigned threads) {
  if (size > fill_capacity_[section]) {
    fill_buffers_[section].reset();
    fill_buffers_[section] = std::unique_ptr<std::uint8_t[]>(new std::uint8_t[size]);  // uninitialised
    fill_capacity_[section] = size;
    // Fresh pages, faulted in by several threads at once rather than one by one as they are filled.
    prefault_for_write({fill_buffers_[section].get(), static_cast<std::size_t>(size)}, threads);
  }
  return {fill_buffers_[section].get(), static_cast<std::size_t>(size)};
}

// A complete section takes no more parts: its buffer's memory goes back before the sections after it are made.
void VxlStreamWriter::release_fill_buffer_if_complete(Section section) {
  const std::size_t i = entry_[section];
  if (i < table_.size() && written_[i] == table_[i].size) {
    fill_buffers_[section].reset();
    fill_capacity_[section] = 0;
  }
}

void VxlStreamWriter::append_meta(const MetaSection& meta) {
  MetaSection m = meta;
  std::memset(m.reserved, 0, sizeof m.reserved);
  append(kMeta, {reinterpret_cast<const std::uint8_t*>(&m), sizeof m});
}

void VxlStreamWriter::append_voxel_index(std::uint64_t buffer_bytes, std::span<std::uint8_t> scratch) {
  const std::size_t x = entry_[kVxix], l = entry_[kVxln], s = entry_[kStrm];
  if (x >= table_.size()) return;
  if (written_[l] != table_[l].size || written_[s] != table_[s].size || written_[x] != 0)
    throw std::logic_error("VxlStreamWriter::append_voxel_index: VXLN or STRM incomplete, or VXIX begun");
  // Both are on the disk already (a direct region writes its last bytes with its last append): read back a part
  // at a time, so that the index costs its buffer and not mappings of the whole tables.
  VoxelIndexIo io;
  io.read_voxlines = [&](std::uint64_t first, std::span<VoxlineEntry> out) {
    out_.pread(out.data(), out.size_bytes(), table_[l].offset + first * sizeof(VoxlineEntry));
  };
  io.read_streamline_table = [&](std::uint64_t first, std::span<std::uint64_t> out) {
    out_.pread(out.data(), out.size_bytes(), table_[s].offset + first * 8);
  };
  io.write = [&](std::span<const std::uint8_t> bytes) { append(kVxix, bytes); };
  if (reinterpret_cast<std::uintptr_t>(scratch.data()) % alignof(IndexedVoxline) != 0)
    throw std::logic_error("VxlStreamWriter::append_voxel_index: scratch not 4-byte aligned");
  io.buffer = {reinterpret_cast<IndexedVoxline*>(scratch.data()), scratch.size() / sizeof(IndexedVoxline)};
  const std::uint64_t voxlines = table_[l].size / sizeof(VoxlineEntry), streamlines = table_[s].size / 8 - 1;
  const std::uint64_t voxels = (table_[x].size - voxlines * sizeof(IndexedVoxline)) / 8 - 1;
  fill_voxel_index(voxels, voxlines, streamlines, io, buffer_bytes);
}

void VxlStreamWriter::append_voxel_index(const VoxelIndexLists& lists) {
  const std::size_t x = entry_[kVxix];
  if (x >= table_.size()) return;
  if (!lists.complete() || written_[x] != 0 ||
      lists.starts().size_bytes() + lists.lists().size_bytes() != table_[x].size)
    throw std::logic_error("VxlStreamWriter::append_voxel_index: lists incomplete or for other counts, or VXIX begun");
  append_items<std::uint64_t>(kVxix, lists.starts());
  append_items<IndexedVoxline>(kVxix, lists.lists());
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
