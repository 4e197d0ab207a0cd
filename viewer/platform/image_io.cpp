#include "viewer/platform/image_io.h"

#include <fcntl.h>
#include <stb_image_write.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <system_error>

#include "format/base/error.h"
#include "format/base/output_path.h"
#include "viewer/platform/picture_module_loader.h"

namespace vxl {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void io_fail(const std::string& what, const std::string& path, const std::string& detail = {}) {
  throw std::runtime_error(what + " '" + path + "'" + (detail.empty() ? "" : ": " + detail));
}

// The output cannot be written (a missing folder, no permission, a full disk): exit 5, not a bug.
[[noreturn]] void output_fail(const std::string& path, const std::string& what, const std::string& detail = {}) {
  throw Error(ErrorKind::Output, path, std::nullopt, what + (detail.empty() ? "" : ": " + detail));
}

// Reserves a unique temporary name next to `target` (O_EXCL, mode 0666 & ~umask, like the final
// file would get). Returns the path; the file exists and is empty. Errors name `shown`, the path as given.
fs::path reserve_temp_file(const fs::path& target, const std::string& shown) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::random_device rd;
  for (int attempt = 0; attempt < 64; ++attempt) {
    const std::string name = "." + target.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                             std::to_string(counter.fetch_add(1)) + "-" + std::to_string(rd() % 100000);
    fs::path tmp = dir / name;
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      ::close(fd);
      return tmp;
    }
    if (errno != EEXIST) output_fail(shown, "cannot create a temporary file in " + dir.string(), std::strerror(errno));
  }
  output_fail(shown, "cannot find a free temporary name in " + dir.string());
}

void fsync_file(const fs::path& p, const std::string& target) {
  const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) output_fail(target, "cannot reopen the temporary file", std::strerror(errno));
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0) output_fail(target, "fsync failed", std::strerror(err));
}

void check_well_formed(const Image& img, const char* which) {
  if (img.width <= 0 || img.height <= 0 ||
      img.rgba.size() != static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 4)
    throw std::runtime_error(std::string("compare_images: image ") + which + " is malformed (" +
                             std::to_string(img.width) + "x" + std::to_string(img.height) + ", " +
                             std::to_string(img.rgba.size()) + " bytes)");
}

}  // namespace

namespace {

// Writes `rgba` as `format` (an OpenImageIO format name) to `path`, atomically (see write_png).
void write_image_as(const std::string& format, const std::string& path, int w, int h,
                    const std::vector<std::uint8_t>& rgba) {
  if (path.empty()) throw std::runtime_error("write_png: empty path");
  if (w <= 0 || h <= 0)
    io_fail("write_png: invalid size " + std::to_string(w) + "x" + std::to_string(h) + " for", path);
  if (rgba.size() != static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4)
    io_fail("write_png: buffer holds " + std::to_string(rgba.size()) + " bytes, " + std::to_string(w) + "x" +
                std::to_string(h) + " RGBA8 needs " + std::to_string(static_cast<std::size_t>(w) * h * 4) + ", for",
            path);

  // PNG and JPEG through stb_image_write (libstb, which the panel's Dear ImGui links anyway): writing the
  // usual picture loads nothing, where OpenImageIO's libraries take half a second. TIFF and OpenEXR through
  // the picture module (OpenImageIO), loaded here on first use.
  const bool with_stb = format == "png" || format == "jpeg";
  const pictures::Api* module = with_stb ? nullptr : &pictures::picture_module(path);
  const fs::path target(output_target(path));
  std::error_code ec;
  const fs::path tmp = reserve_temp_file(target, path);
  try {
    // The format is named explicitly: the temporary name's extension is not the output's.
    if (with_stb) {
      errno = 0;
      // Straight alpha, the bytes as given; JPEG keeps the colour channels (quality 95).
      const int written = format == "png" ? stbi_write_png(tmp.c_str(), w, h, 4, rgba.data(), w * 4)
                                          : stbi_write_jpg(tmp.c_str(), w, h, 4, rgba.data(), 95);
      if (written == 0)
        output_fail(path, "cannot write the " + format + " picture", errno != 0 ? std::strerror(errno) : "");
    } else {
      std::string error;
      switch (module->write(format.c_str(), tmp.c_str(), w, h, rgba.data(), error)) {
        case pictures::WriteStatus::Ok: break;
        case pictures::WriteStatus::NoWriter: io_fail("OpenImageIO has no " + format + " writer for", path, error);
        case pictures::WriteStatus::OutputFailed: output_fail(path, error);
      }
    }
    fsync_file(tmp, path);
    fs::rename(tmp, target, ec);
    if (ec) output_fail(path, "cannot rename the temporary file into place", ec.message());
  } catch (...) {
    std::error_code ignore;
    fs::remove(tmp, ignore);
    throw;
  }
}

}  // namespace

void write_png(const std::string& path, int w, int h, const std::vector<std::uint8_t>& rgba) {
  write_image_as("png", path, w, h, rgba);
}

namespace {

// The pictures voxview writes, in one table: OpenImageIO's format name, the name messages give, the extensions.
struct PictureFormat {
  const char* format;
  const char* label;
  std::vector<const char*> extensions;
};
const std::vector<PictureFormat>& picture_formats() {
  static const std::vector<PictureFormat> formats = {{"png", "PNG", {".png"}},
                                                     {"jpeg", "JPEG", {".jpg", ".jpeg"}},
                                                     {"tiff", "TIFF", {".tif", ".tiff"}},
                                                     {"openexr", "OpenEXR", {".exr"}}};
  return formats;
}

}  // namespace

std::string picture_format_of(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext.empty()) return "png";
  for (const PictureFormat& f : picture_formats())
    for (const char* e : f.extensions)
      if (ext == e) return f.format;
  return {};
}

std::string picture_formats_text() {
  std::string text;
  const auto& formats = picture_formats();
  for (std::size_t i = 0; i < formats.size(); ++i) {
    text += i == 0 ? "" : i + 1 == formats.size() ? " or " : ", ";
    text += std::string(formats[i].label) + " (";
    for (std::size_t k = 0; k < formats[i].extensions.size(); ++k)
      text += std::string(k ? ", " : "") + formats[i].extensions[k];
    text += ")";
  }
  return text;
}

void write_picture(const std::string& path, int w, int h, const std::vector<std::uint8_t>& rgba) {
  const std::string format = picture_format_of(path);
  if (format.empty())
    throw Error(ErrorKind::Usage, path, std::nullopt,
                std::string("the extension names no picture format voxview writes: use ") + picture_formats_text());
  write_image_as(format, path, w, h, rgba);
}

Image read_image(const std::string& path) {
  Image img;
  std::string error;
  if (!pictures::picture_module(path).read(path.c_str(), img.width, img.height, img.rgba, error))
    io_fail("read_image: cannot read", path, error);
  return img;
}

ImageDiff compare_images(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height)
    throw std::runtime_error("compare_images: sizes differ (" + std::to_string(a.width) + "x" +
                             std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                             std::to_string(b.height) + ")");
  check_well_formed(a, "a");
  check_well_formed(b, "b");
  // Thresholds 0: every pixel with any differing channel counts as a failure.
  pictures::Comparison r;
  std::string error;
  if (!pictures::picture_module("").compare(a.width, a.height, a.rgba.data(), b.rgba.data(), 4, 0.0f, 0.0f, r, error))
    throw std::runtime_error("compare_images: OpenImageIO compare failed: " + error);
  ImageDiff d;
  d.mean_error = r.mean_error;
  d.rms_error = r.rms_error;
  d.psnr = r.psnr;
  d.max_error = r.max_error;
  d.max_x = r.max_x;
  d.max_y = r.max_y;
  d.max_channel = r.max_channel;
  d.differing_pixels = r.failing_pixels;
  return d;
}

}  // namespace vxl
