#include "converter/readers/image_file.h"

#include <cctype>
#include <filesystem>

#include "converter/readers/regular_file.h"
#include "format/base/error.h"

namespace vxl {
namespace {

MappedFile open_image(const std::string& path, const std::string& format) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    fail_input(path, std::nullopt, "no such file (expected " + format + " image)");
  require_regular_file(path);
  return MappedFile(path);
}

}  // namespace

ImageFile::ImageFile(const std::string& path, const std::string& format)
    : path_(path), file_(open_image(path, format)) {
  cap_ = inflate_cap(file_.size()) - kInflateSlack + kImageInflateSlack;
  if (is_gzip(file_.bytes())) {
    // Read as its name says, as MRtrix reads it: gzip data in a file not named .gz is not that format's.
    std::string lower = path;
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (!lower.ends_with(".gz"))
      fail_input(path, 0,
                 "holds gzip-compressed data but is not named .gz (rename it " +
                     std::filesystem::path(path).filename().string() + ".gz)");
    stream_.emplace(path, file_.bytes(), warnings_, cap_, "real images compress about 2-10x, masks far more");
  } else
    stream_.emplace(file_.bytes());
}

void ImageFile::check_claim(double needed, const std::string& claim) const {
  if (gzipped() && needed > double(cap_))
    fail_unsupported(path_, claim + " need " + std::to_string(static_cast<std::uint64_t>(needed)) + " bytes, over " +
                                std::to_string(kMaxInflateRatio) + " times the compressed size (" +
                                std::to_string(file_.size()) + " bytes) plus " +
                                std::to_string(kImageInflateSlack >> 20) +
                                " MiB; refused as a likely decompression bomb. To read it anyway, gunzip it first");
}

void ImageFile::finish() {
  if (gzipped())
    while (!stream_->at_end()) stream_->skip(stream_->left());
}

}  // namespace vxl
