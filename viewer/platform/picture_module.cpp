// libvoxlines_pictures.so: OpenImageIO's writers, readers and comparison behind picture_module.h's table.
// Nothing of the project is linked in: the atomic output, the format table and the errors stay in
// image_io.cpp, which loads this module on first use.
#include "viewer/platform/picture_module.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <exception>

namespace {

using vxl::pictures::Comparison;
using vxl::pictures::WriteStatus;

WriteStatus write(const char* format, const char* path, int w, int h, const std::uint8_t* rgba,
                  std::string& error) noexcept {
  try {
    const std::string name = format;
    auto out = OIIO::ImageOutput::create(name);
    if (!out) {
      error = OIIO::geterror();
      return WriteStatus::NoWriter;
    }
    // JPEG holds no alpha: write the colour channels only (a stride of 4 bytes a pixel skips it).
    const int channels = name == "jpeg" ? 3 : 4;
    OIIO::ImageSpec spec(w, h, channels, name == "openexr" ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8);
    // Straight alpha: write the bytes verbatim (OpenImageIO would un-premultiply PNG output otherwise).
    if (channels == 4) spec.attribute("oiio:UnassociatedAlpha", 1);
    if (name == "jpeg") spec.attribute("CompressionQuality", 95);
    const std::string what = "the " + name + " picture";
    if (!out->open(path, spec)) {
      error = "cannot open " + what + " for writing: " + out->geterror();
      return WriteStatus::OutputFailed;
    }
    if (!out->write_image(OIIO::TypeDesc::UINT8, rgba, 4)) {
      error = "cannot write " + what + ": " + out->geterror();
      out->close();
      return WriteStatus::OutputFailed;
    }
    if (!out->close()) {
      error = "cannot finish " + what + ": " + out->geterror();
      return WriteStatus::OutputFailed;
    }
    return WriteStatus::Ok;
  } catch (const std::exception& e) {
    error = e.what();
    return WriteStatus::OutputFailed;
  }
}

bool read(const char* path, int& w, int& h, std::vector<std::uint8_t>& rgba, std::string& error) noexcept {
  try {
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);  // keep the file's straight alpha (no premultiply)
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) {
      error = "cannot open: " + OIIO::geterror();
      return false;
    }
    const OIIO::ImageSpec& spec = in->spec();
    const int nch = spec.nchannels;
    if (spec.width <= 0 || spec.height <= 0 || nch <= 0 || spec.depth > 1) {
      error = "unsupported image layout";
      return false;
    }
    std::vector<std::uint8_t> raw(static_cast<std::size_t>(spec.width) * spec.height * nch);
    if (!in->read_image(0, 0, 0, nch, OIIO::TypeDesc::UINT8, raw.data())) {
      error = "cannot read: " + in->geterror();
      return false;
    }
    in->close();
    w = spec.width;
    h = spec.height;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    rgba.resize(n * 4);
    int alpha = spec.alpha_channel;
    if (alpha < 0 || alpha >= nch) alpha = nch == 2 ? 1 : nch >= 4 ? 3 : -1;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint8_t* s = raw.data() + i * nch;
      std::uint8_t* d = rgba.data() + i * 4;
      for (int c = 0; c < 3; ++c) d[c] = nch >= 3 ? s[c] : s[0];
      d[3] = alpha >= 0 ? s[alpha] : 255;
    }
    return true;
  } catch (const std::exception& e) {
    error = e.what();
    return false;
  }
}

bool compare(int w, int h, const std::uint8_t* a, const std::uint8_t* b, int channels, float fail_threshold,
             float warn_threshold, Comparison& result, std::string& error) noexcept {
  try {
    const OIIO::ImageSpec spec(w, h, 4, OIIO::TypeDesc::UINT8);
    // ImageBuf wraps the caller's memory; compare() only reads it.
    const OIIO::ImageBuf A(spec, const_cast<std::uint8_t*>(a)), B(spec, const_cast<std::uint8_t*>(b));
    const OIIO::ROI roi(0, w, 0, h, 0, 1, 0, channels);
    const OIIO::ImageBufAlgo::CompareResults r = OIIO::ImageBufAlgo::compare(A, B, fail_threshold, warn_threshold, roi);
    // `error` is also set when a pixel passes a threshold: only an error without such pixels is a failure.
    if (r.error && r.nfail == 0 && r.nwarn == 0) {
      error = OIIO::geterror();
      return false;
    }
    result = {r.meanerror, r.rms_error, r.PSNR, r.maxerror, r.maxx, r.maxy, r.maxc, r.nfail, r.nwarn};
    return true;
  } catch (const std::exception& e) {
    error = e.what();
    return false;
  }
}

constexpr vxl::pictures::Api kApi = {vxl::pictures::kAbiVersion, write, read, compare};

}  // namespace

extern "C" __attribute__((visibility("default"))) const vxl::pictures::Api* voxlines_picture_api() { return &kApi; }
