// A .vxl file's coarser levels of detail (spec §5.12) as a .vxl of their own, made from a few of its bytes: for a
// reader that cannot hold the file (the web viewer, whose 32-bit memory holds at most kWebMaxFileBytes) but can draw
// the levels that fit. The image's level d is the file's level `level + d`: each voxel's block is the prefix that
// level holds and its orders are that level's and the coarser ones', which lie at the end of the voxel's orders.
//
// A reader fetches the file's tables (ranges_for_level_image), makes the image from them (make_level_image: the
// tables rewritten, the rest to come), opens it with VxlFile::open, and fetches the image's vertex and order bytes
// from where `data` says they lie in the file, as it would fetch a file's own ranges (source_ranges). The image has
// no voxlines and no streamline table, values or groups (they are per streamline or per full-detail vertex): it
// draws in the sorted modes alone.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "format/base/mapped_file.h"
#include "format/vxl_fetch_plan.h"
#include "format/vxl_file.h"
#include "format/vxl_layout.h"

namespace vxl {

// Bytes [source, source + size) of the file go to [at, at + size) of the image.
struct ImagePlacement {
  std::uint64_t source = 0, size = 0, at = 0;
};

struct LevelImage {
  MappedFile bytes;         // the image: every byte but those `data` places is written (its VERT and ORDB to come)
  std::uint32_t level = 0;  // the file's level that is the image's level 0
  MetaSection file_meta{};  // the file's own META (its streamline count, its levels)
  // The image's vertex and order bytes in the file, in file order (and so in image order), one run per voxel and
  // section; the checksums of the image's VERT and ORDB are zero (their bytes arrive later: the draw checks check
  // what is drawn, as for any file read by ranges).
  std::vector<ImagePlacement> data;
  std::vector<ByteRange> written;  // the image's bytes that are in: all but data's
};

// What make_level_image reads of a file of `file_size` bytes whose first bytes are `first` (at least the header and
// the section table; checked as VxlFile::open checks them, throwing as it does): the header and the section table,
// then META, DIRS, VDIR, VOXT, LODS and PROV whole. Sorted and disjoint.
std::vector<ByteRange> ranges_for_level_image(const std::string& path, std::span<const std::uint8_t> first,
                                              std::uint64_t file_size);

// The image of the finest level whose image takes at most `max_bytes`, from `gathered`: the bytes of
// ranges_for_level_image one after another. Each table is checked against its checksum (and the header against its
// own), each voxel's vertex and order runs against their sections; vxl::Error (Input, naming the file's byte) when
// one is not, (Unsupported) when not even the coarsest level's image fits. VxlFile::open(std::move(image.bytes))
// then checks the image as any file.
LevelImage make_level_image(const std::string& path, std::span<const std::uint8_t> gathered, std::uint64_t file_size,
                            std::uint64_t max_bytes);

// The level make_level_image chooses for `file` under `max_bytes`, and its image's size; nullopt where not even the
// coarsest level's image fits. For a writer that tells whether a reader will draw the file, and from which level.
struct LevelImageSize {
  std::uint32_t level = 0;
  std::uint64_t bytes = 0;
};
std::optional<LevelImageSize> level_image_size(const VxlFile& file, std::uint64_t max_bytes);

// Where `image_ranges` (of the image's VERT and ORDB, sorted) lie in the file, merged where less than `gap` bytes lie
// between two.
std::vector<ByteRange> source_ranges(std::span<const ImagePlacement> data, std::span<const ByteRange> image_ranges,
                                     std::uint64_t gap);

}  // namespace vxl
