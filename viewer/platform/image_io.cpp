#include "viewer/platform/image_io.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <fcntl.h>
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

OIIO::ImageBuf wrap(const Image& img, const char* which) {
  if (img.width <= 0 || img.height <= 0 ||
      img.rgba.size() != static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 4)
    throw std::runtime_error(std::string("compare_images: image ") + which + " is malformed (" +
                             std::to_string(img.width) + "x" + std::to_string(img.height) + ", " +
                             std::to_string(img.rgba.size()) + " bytes)");
  OIIO::ImageSpec spec(img.width, img.height, 4, OIIO::TypeDesc::UINT8);
  // ImageBuf wraps the caller's memory; compare() only reads it.
  return OIIO::ImageBuf(spec, const_cast<std::uint8_t*>(img.rgba.data()));
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

  const fs::path target(output_target(path));
  std::error_code ec;
  const fs::path tmp = reserve_temp_file(target, path);
  try {
    // The format is named explicitly: the temporary name's extension is not the output's.
    auto out = OIIO::ImageOutput::create(format);
    if (!out) io_fail("OpenImageIO has no " + format + " writer for", path, OIIO::geterror());
    // JPEG holds no alpha: write the colour channels only (a stride of 4 bytes a pixel skips it).
    const int channels = format == "jpeg" ? 3 : 4;
    OIIO::ImageSpec spec(w, h, channels, format == "openexr" ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8);
    if (channels == 4) spec.attribute("oiio:UnassociatedAlpha", 1);  // straight alpha: write the bytes verbatim
    if (format == "jpeg") spec.attribute("CompressionQuality", 95);
    const std::string what = "the " + format + " picture";
    if (!out->open(tmp.string(), spec)) output_fail(path, "cannot open " + what + " for writing", out->geterror());
    if (!out->write_image(OIIO::TypeDesc::UINT8, rgba.data(), 4)) {
      const std::string err = out->geterror();
      out->close();
      output_fail(path, "cannot write " + what, err);
    }
    if (!out->close()) output_fail(path, "cannot finish " + what, out->geterror());
    out.reset();
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
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);  // keep the file's straight alpha (no premultiply)
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) io_fail("read_image: cannot open", path, OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  const int nch = spec.nchannels;
  if (spec.width <= 0 || spec.height <= 0 || nch <= 0 || spec.depth > 1)
    io_fail("read_image: unsupported image layout in", path);

  std::vector<std::uint8_t> raw(static_cast<std::size_t>(spec.width) * spec.height * nch);
  if (!in->read_image(0, 0, 0, nch, OIIO::TypeDesc::UINT8, raw.data()))
    io_fail("read_image: cannot read", path, in->geterror());
  in->close();

  Image img;
  img.width = spec.width;
  img.height = spec.height;
  img.rgba.resize(static_cast<std::size_t>(img.width) * img.height * 4);
  int alpha = spec.alpha_channel;
  if (alpha < 0 || alpha >= nch) alpha = nch == 2 ? 1 : nch >= 4 ? 3 : -1;
  const std::size_t n = static_cast<std::size_t>(img.width) * img.height;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* s = raw.data() + i * nch;
    std::uint8_t* d = img.rgba.data() + i * 4;
    if (nch >= 3) {
      d[0] = s[0];
      d[1] = s[1];
      d[2] = s[2];
    } else {
      d[0] = d[1] = d[2] = s[0];
    }
    d[3] = alpha >= 0 ? s[alpha] : 255;
  }
  return img;
}

ImageDiff compare_images(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height)
    throw std::runtime_error("compare_images: sizes differ (" + std::to_string(a.width) + "x" +
                             std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                             std::to_string(b.height) + ")");
  const OIIO::ImageBuf A = wrap(a, "a");
  const OIIO::ImageBuf B = wrap(b, "b");
  // failthresh 0: every pixel with any differing channel counts as a failure.
  const OIIO::ImageBufAlgo::CompareResults r = OIIO::ImageBufAlgo::compare(A, B, 0.0f, 0.0f);
  // CompareResults::error is also set when any pixel exceeds failthresh (always, with 0 here):
  // only an error without failing pixels is a real failure.
  if (r.error && r.nfail == 0 && r.nwarn == 0)
    throw std::runtime_error("compare_images: OpenImageIO compare failed: " + OIIO::geterror());
  ImageDiff d;
  d.mean_error = r.meanerror;
  d.rms_error = r.rms_error;
  d.psnr = r.PSNR;
  d.max_error = r.maxerror;
  d.max_x = r.maxx;
  d.max_y = r.maxy;
  d.max_channel = r.maxc;
  d.differing_pixels = r.nfail;
  return d;
}

}  // namespace vxl
