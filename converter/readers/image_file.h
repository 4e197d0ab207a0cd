// An image file's bytes for the image readers (NIfTI, MRtrix): mapped, and inflated through
// converter/readers/gzip_bytes.h when it starts with the gzip magic, whatever its name. A gzipped image
// may inflate to kMaxInflateRatio times its size plus kImageInflateSlack: masks are mostly zeros and
// compress far more than other data, so any image of up to 64 MiB passes whatever its ratio.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "converter/readers/gzip_bytes.h"
#include "format/base/mapped_file.h"

namespace vxl {

inline constexpr std::uint64_t kImageInflateSlack = std::uint64_t(64) << 20;

class ImageFile {
 public:
  // Throws vxl::Error (Input) when `path` is missing ("expected a `format` image") or not a regular file.
  ImageFile(const std::string& path, const std::string& format);

  GzipBytes& bytes() { return *stream_; }
  bool gzipped() const { return stream_->compressed(); }
  std::uint64_t file_size() const { return file_.size(); }
  // What follows an offset in messages: offsets of a gzipped file count its decompressed bytes.
  std::string offset_note() const { return gzipped() ? " (offset in the decompressed data)" : ""; }

  // Refuses (exit 4), before anything is inflated, a gzipped file whose header says it holds `needed`
  // bytes beyond what it may inflate to; `claim` says what the header claims ("the header's 4x4x4 voxels").
  void check_claim(double needed, const std::string& claim) const;
  // Inflates (and drops) the rest of a gzip stream, so that its CRC and what follows it are checked.
  void finish();

 private:
  std::string path_;
  MappedFile file_;
  std::vector<std::string> warnings_;  // zero padding after the gzip stream: harmless, and images keep no provenance
  std::uint64_t cap_ = 0;
  std::optional<GzipBytes> stream_;
};

}  // namespace vxl
