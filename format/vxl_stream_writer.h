// Writes a .vxl file (spec §2–§5) whose payloads are produced piece by piece, in bounded memory: each
// section's bytes are appended in order (sections may be interleaved), written with pwrite at their
// final offsets or filled in place through a mapping that is dropped when the part is done (with direct writes:
// in a buffer, kept for the section's next part until the section is complete). Each section is checksummed
// as it is appended; commit() checks that every payload is complete, writes the section table and the
// header, and links the file into place (AtomicOutputFile), so a partial file never appears.
//
// The layout is plan_vxl_layout's (vxl_sections.h).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "format/base/atomic_output.h"
#include "format/base/checksum.h"
#include "format/base/direct_region_writer.h"
#include "format/base/parallel.h"
#include "format/vxl_layout.h"
#include "format/vxl_sections.h"

namespace vxl {

class VoxelIndexLists;

class VxlStreamWriter : public VxlSections {
 public:
  using Section = Index;

  // Creates the output at `path`, sized for these payloads (which read as zero until written).
  // Throws vxl::Error (Output).
  // With `direct_staging_bytes` > 0 the payloads bypass the page cache where the file system allows
  // (DirectRegionWriter, staged that many bytes at a time per section); the file's bytes are the same.
  VxlStreamWriter(const std::string& path, const VxlSectionSizes& sizes, std::uint64_t direct_staging_bytes = 0);
  VxlStreamWriter(const VxlStreamWriter&) = delete;
  VxlStreamWriter& operator=(const VxlStreamWriter&) = delete;

  // Appends to a payload. Throws std::logic_error past the payload's planned size (or for kGrps when
  // there is no GRPS section), vxl::Error (Output) when the write fails.
  void append(Section section, std::span<const std::uint8_t> bytes);
  // Where byte `at` of `section`'s payload falls in its 4 KiB block of the file (DirectRegionWriter::kBlock).
  std::uint64_t block_lead(Section section, std::uint64_t at) const;
  // Appends the `size` bytes at block + block_lead(section, bytes appended so far), as append does; with direct
  // writes their whole blocks go to the file straight from `block` (block-aligned; the writer may overwrite the
  // bytes before them in it) instead of being copied through the staging (DirectRegionWriter::append_from_block).
  void append_from_block(Section section, std::uint8_t* block, std::uint64_t size);
  template <typename T>
  void append_items(Section section, std::span<const T> items) {
    append(section, {reinterpret_cast<const std::uint8_t*>(items.data()), items.size_bytes()});
  }
  // Appends `size` bytes that fill(std::span<std::uint8_t>) writes in place — every one of them — through
  // a mapping of the output (its pages faulted in ahead by up to `threads` threads), so that a large part
  // needs no buffer of its own and no copy; then calls then(std::span<const std::uint8_t>), which may
  // still read the part. Appends to other sections may happen inside both. The part is checksummed and
  // unmapped when then() returns. With direct writes the part is filled in a buffer (kept for the
  // section's next part, and let go once the section is complete), mapping it would put it in the page cache,
  // and written out on another thread while then() runs.
  template <typename Fill, typename Then>
  void append_in_place(Section section, std::uint64_t size, unsigned threads, Fill&& fill, Then&& then) {
    if (!regions_.empty()) {
      const std::span<std::uint8_t> buffer = fill_buffer(section, size, threads);
      fill(buffer);
      BackgroundTask<> writing([&] { append(section, buffer); });
      then(std::span<const std::uint8_t>(buffer));  // on a throw, `writing` waits for the write first
      writing.get();
      release_fill_buffer_if_complete(section);
      return;
    }
    FileWindow window = open_window(section, size, threads);
    fill(window.bytes());
    then(std::span<const std::uint8_t>(window.bytes()));
    close_window(section, window);
  }
  // For a payload produced out of order (VERT, placed voxel by voxel in streamline order) without a
  // buffer of its size: region_writer() writes bytes [offset, offset + size) of the payload, appended in
  // order (direct where the file system allows, staged `staging_bytes` at a time, in `staging_memory` if
  // given: see DirectRegionWriter); the regions may be
  // written in any order, each must be complete before it is read back. read_back() then reads the
  // payload's next `size` bytes into `buffer` (block-aligned, at least read_back_bytes(size): the blocks
  // around them), past the page cache where allowed, checksums them and counts them as appended: a
  // payload written this way is read back whole, in order.
  std::unique_ptr<DirectRegionWriter> region_writer(Section section, std::uint64_t offset, std::uint64_t size,
                                                    std::uint64_t staging_bytes, std::uint8_t* staging_memory = nullptr,
                                                    DirectWriteQueue* queue = nullptr);
  // A queue that region writers hand their full staging to (DirectWriteQueue), writing to this file.
  std::unique_ptr<DirectWriteQueue> write_queue(std::vector<std::uint8_t*> spares, std::uint64_t buffer_bytes);
  static std::uint64_t read_back_bytes(std::uint64_t size);
  std::span<const std::uint8_t> read_back(Section section, std::uint64_t size, std::span<std::uint8_t> buffer);

  void append_meta(const MetaSection& meta);  // zeroes the reserved bytes
  std::uint64_t written(Section section) const {
    return entry_[section] < table_.size() ? written_[entry_[section]] : 0;
  }

  // Appends VXIX (spec §5.14), when the file has one, from VXLN and STRM, which must be complete: read back a
  // part at a time, the lists sorted in a buffer of up to `buffer_bytes` (a voxel's list larger than that
  // alone), one pass over both tables per buffer full besides the one that counts the lists. `scratch`, where
  // given, is the caller's memory for that buffer (4-byte aligned).
  void append_voxel_index(std::uint64_t buffer_bytes, std::span<std::uint8_t> scratch = {});
  // Appends VXIX from lists filled as VXLN was made (`lists` complete, for this file's counts).
  void append_voxel_index(const VoxelIndexLists& lists);

  // Throws std::logic_error unless every payload has been appended in full; then writes the table and
  // the header and links the file into place. Without commit() the destructor discards the file.
  void commit();

 private:
  FileWindow open_window(Section section, std::uint64_t size, unsigned threads);
  void close_window(Section section, FileWindow& window);
  std::span<std::uint8_t> fill_buffer(Section section, std::uint64_t size, unsigned threads);
  void release_fill_buffer_if_complete(Section section);

  AtomicOutputFile out_;
  PositionEncoding positions_;
  std::vector<SectionEntry> table_;  // in Section order, optional sections (VDIR, LODS, GRPS) only when present
  std::size_t entry_[kCount];        // Section -> index in table_ (table_.size(): absent)
  std::uint64_t file_size_ = 0;
  std::vector<std::uint64_t> written_;
  std::vector<std::unique_ptr<Xxh3_64Stream>> checksums_;
  std::vector<std::unique_ptr<DirectRegionWriter>> regions_;  // per table_ entry, with direct writes
  int direct_fd_ = -1;  // the output opened with O_DIRECT (-1: none, or the file system refused it)
  // append_in_place's buffers, with direct writes
  std::unique_ptr<std::uint8_t[]> fill_buffers_[kCount];
  std::uint64_t fill_capacity_[kCount] = {};
};

}  // namespace vxl
