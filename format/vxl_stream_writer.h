// Writes a .vxl file (spec §2–§5) whose payloads are produced piece by piece, in bounded memory: each
// section's bytes are appended in order (sections may be interleaved), written with pwrite at their
// final offsets or filled in place through a mapping that is dropped when the part is done, so nothing of
// the output stays in this process's memory. Each section is checksummed
// as it is appended; commit() checks that every payload is complete, writes the section table and the
// header, and links the file into place (AtomicOutputFile), so a partial file never appears.
//
// The layout is VxlWriter's (plan_vxl_layout): the same content gives the same bytes either way.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "format/atomic_output.h"
#include "format/checksum.h"
#include "format/vxl_layout.h"
#include "format/vxl_writer.h"

namespace vxl {

class VxlStreamWriter : public VxlSections {
 public:
  using Section = Index;  // VVAL and SVAL: never planned here, so appending to them throws

  // Creates the output at `path`, sized for these payloads (which read as zero until written).
  // Throws vxl::Error (Output).
  VxlStreamWriter(const std::string& path, const VxlSectionSizes& sizes);
  VxlStreamWriter(const VxlStreamWriter&) = delete;
  VxlStreamWriter& operator=(const VxlStreamWriter&) = delete;

  // Appends to a payload. Throws std::logic_error past the payload's planned size (or for kGrps when
  // there is no GRPS section), vxl::Error (Output) when the write fails.
  void append(Section section, std::span<const std::uint8_t> bytes);
  template <typename T>
  void append_items(Section section, std::span<const T> items) {
    append(section, {reinterpret_cast<const std::uint8_t*>(items.data()), items.size_bytes()});
  }
  // Appends `size` bytes that fill(std::span<std::uint8_t>) writes in place, through a mapping of the
  // output (its pages faulted in ahead by up to `threads` threads; they read as zero until written), so
  // that a large part needs no buffer of its own and no copy. Appends to other sections may happen
  // inside fill(). The part is checksummed and unmapped when fill() returns.
  template <typename Fill>
  void append_in_place(Section section, std::uint64_t size, unsigned threads, Fill&& fill) {
    AtomicOutputFile::Window window = open_window(section, size, threads);
    fill(window.bytes());
    close_window(section, window);
  }
  void append_meta(const MetaSection& meta);  // zeroes the reserved bytes
  std::uint64_t written(Section section) const {
    return entry_[section] < table_.size() ? written_[entry_[section]] : 0;
  }

  // Throws std::logic_error unless every payload has been appended in full; then writes the table and
  // the header and links the file into place. Without commit() the destructor discards the file.
  void commit();

 private:
  AtomicOutputFile::Window open_window(Section section, std::uint64_t size, unsigned threads);
  void close_window(Section section, AtomicOutputFile::Window& window);

  AtomicOutputFile out_;
  PositionEncoding positions_;
  std::vector<SectionEntry> table_;  // in Section order, optional sections (VDIR, LODS, GRPS) only when present
  std::size_t entry_[kCount];        // Section -> index in table_ (table_.size(): absent)
  std::uint64_t file_size_ = 0;
  std::vector<std::uint64_t> written_;
  std::vector<std::unique_ptr<Xxh3_64Stream>> checksums_;
};

}  // namespace vxl
