// The .vxlz package container (spec/vxlz-package-v2.md §2, §8): a writer that checksums the sections and
// writes the file atomically, and a reader that validates the header, the section table, every checksum
// and the fixed-size sections before anything is decoded, so that a damaged or truncated package is
// refused with an Error naming the file, the byte offset and what was expected.
//
// The container knows the sections' encodings (raw, zlib) but not their meaning: vxlz_tables.h encodes
// and decodes the exact tables, vxlz_draco.h the position chunks, converter/pack and converter/unpack
// put them together.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "format/base/mapped_file.h"
#include "format/vxl_layout.h"
#include "format/vxlz_draco.h"
#include "format/vxlz_layout.h"
#include "format/vxlz_streams.h"

namespace vxl {

// Everything a package holds, before compression. The varint streams are the raw (inflated) bytes of
// spec §4; write_vxlz deflates them.
struct VxlzContent {
  PackSection pack{};  // reserved bytes are zeroed by the writer
  MetaSection meta{};
  std::vector<DirectionEntry> directions;
  std::vector<std::uint8_t> voxel_coords;                 // VOXC
  std::vector<std::uint8_t> streamline_voxlines;          // STRL
  std::vector<std::uint8_t> voxline_voxels;               // VXLV
  std::vector<std::uint8_t> voxline_counts;               // VXLC
  std::optional<std::string> provenance;                  // PROV, when the .vxl has one
  std::optional<std::vector<std::uint8_t>> groups;        // GRPS, when the .vxl has groups
  std::optional<std::vector<std::uint8_t>> group_values;  // GDAT (the .vxl payload), when the .vxl has it
  // PVAL / SVAL payloads (encode_value_section, already deflated), when the .vxl has VVAL / SVAL.
  std::optional<std::vector<std::uint8_t>> point_values, streamline_values;
  std::vector<EncodedChunk> chunks;  // Draco buffers, one pair per position chunk
};

// The zlib payloads of the table sections (spec §4), deflated side by side on up to `threads` threads
// (0: all cores). Separate from write_vxlz so that a packer can deflate them while it encodes the
// positions. Throws vxl::Error (Output).
struct DeflatedTables {
  std::vector<std::uint8_t> voxel_coords, streamline_voxlines, voxline_voxels, voxline_counts;
  std::optional<std::vector<std::uint8_t>> provenance, groups, group_values;  // when the content has them
};
DeflatedTables deflate_tables(const VxlzContent& content, unsigned threads = 0);

// Writes the package atomically, its table sections from `tables` (deflated from `content`); the
// second form deflates them first. Returns the package's size in bytes. Throws vxl::Error (Output)
// naming the path.
std::uint64_t write_vxlz(const std::string& path, const VxlzContent& content, const DeflatedTables& tables);
std::uint64_t write_vxlz(const std::string& path, const VxlzContent& content, unsigned threads = 0);

// Whether the file at `path` starts as a package does (its magic), to tell a .vxlz from a .vxl whatever its name.
// Throws vxl::Error (Input) when it cannot be opened or is not a regular file.
bool starts_as_vxlz(const std::string& path);

class VxlzFile {
 public:
  // Maps and validates spec §8 steps 1-4. Throws vxl::Error (Input; Unsupported for an unknown major
  // version or required section).
  static VxlzFile open(const std::string& path);
  // The same, of bytes already in memory (named by file.path() in errors).
  static VxlzFile open(MappedFile file);
  // The first bytes of a package still arriving (`prefix`: its bytes so far): validated as open() validates a
  // whole package, except that the positions (POSD) may be cut short and their checksum is not checked; every
  // other section must be whole (else Input, "needs the first N bytes"). Chunks past the prefix are not there
  // (chunks_present). Those present are checked against their own checksums where the package has them (CHKS,
  // version 2.4), and only where it has them: has_chunk_checksums().
  static VxlzFile open_prefix(MappedFile prefix);
  // Where the positions (POSD) start, read from a package's first bytes (unchecked: open_prefix checks): nullopt while
  // they do not hold its section table yet, 0 when the table names no POSD. A prefix that reaches it can be opened.
  static std::optional<std::uint64_t> positions_offset(std::span<const std::uint8_t> first_bytes);

  const std::string& path() const { return file_.path(); }
  std::uint64_t size() const { return file_.size(); }
  const FileHeader& header() const { return header_; }
  std::span<const SectionEntry> sections() const { return sections_; }
  const PackSection& pack() const { return pack_; }
  const MetaSection& meta() const { return meta_; }
  std::span<const DirectionEntry> directions() const { return directions_; }

  bool has_section(std::uint32_t id) const { return find(id) != nullptr; }
  bool has_chunk_checksums() const { return has_section(section_id("CHKS")); }
  // A zlib section inflated (spec §8 step 5); empty when an optional section is absent.
  std::vector<std::uint8_t> inflate(std::uint32_t id) const;
  // A section's payload as stored (empty when an optional section is absent).
  std::span<const std::uint8_t> section_payload(std::uint32_t id) const {
    const SectionEntry* e = find(id);
    return e ? payload(*e) : std::span<const std::uint8_t>();
  }
  // Where errors about an inflated stream point: the section and its offset.
  StreamContext context(std::uint32_t id) const;

  std::uint64_t chunk_count() const { return (chunk_offsets_.size() - 1) / 2; }
  // The chunks whose bytes are all in the file: all of them, unless it was opened as a prefix.
  std::uint64_t chunks_present() const;
  // Chunk i's symbol and escape buffers and where they lie in the file (i < chunks_present()).
  ChunkBytes chunk(std::uint64_t i) const;
  // Where the first `count` chunks end in the file (count <= chunk_count()).
  std::uint64_t chunks_end(std::uint64_t count) const { return posd_offset_ + chunk_offsets_[2 * count]; }
  // Points in chunk i (chunk_points, fewer in the last).
  std::uint64_t chunk_point_count(std::uint64_t i) const;

 private:
  explicit VxlzFile(MappedFile file, bool prefix = false) : file_(std::move(file)), prefix_(prefix) {}
  void validate();
  void validate_header_and_table();
  void validate_checksums() const;
  void validate_pack_and_meta();
  void validate_chunks();
  void validate_chunk_checksums() const;
  const SectionEntry* find(std::uint32_t id) const;
  std::span<const std::uint8_t> payload(const SectionEntry& e) const { return file_.bytes().subspan(e.offset, e.size); }

  MappedFile file_;
  FileHeader header_{};
  std::vector<SectionEntry> sections_;
  PackSection pack_{};
  MetaSection meta_{};
  std::vector<DirectionEntry> directions_;
  // 2 chunk_count + 1 offsets inside POSD: chunk i's symbols start at [2i], its escapes at [2i + 1].
  std::vector<std::uint64_t> chunk_offsets_{0};
  std::uint64_t posd_offset_ = 0;
  bool prefix_ = false;  // the file is the first bytes of a package: POSD may be cut short
};

}  // namespace vxl
