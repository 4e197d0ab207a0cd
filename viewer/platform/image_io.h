#pragma once
// Image files: PNG, JPEG, TIFF or OpenEXR output (atomic), RGBA8 input and numeric comparison. PNG and JPEG
// are written with stb_image_write; TIFF and OpenEXR, reading and comparing with OpenImageIO, in a module
// loaded on first use (picture_module.h).
//
// Alpha is straight (unassociated) on both sides: the bytes given to write_png are the bytes in the
// file, and read_image returns the file's bytes. (OpenImageIO would otherwise un-premultiply on PNG
// output and premultiply on PNG input.)

#include <cstdint>
#include <string>
#include <vector>

namespace vxl {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;  // width*height*4 bytes, rows top-to-bottom

  std::uint8_t* pixel(int x, int y) { return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4; }
  const std::uint8_t* pixel(int x, int y) const { return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4; }
};

// Writes an RGBA8 PNG (rows top-to-bottom, rgba.size() == w*h*4). Atomic: the image is written to a
// temporary file in the same directory, flushed, then renamed over `path`; on failure the temporary
// file is removed and `path` is untouched (no new or partial file there). `path` follows the output
// rule of format/base/output_path.h (a device, FIFO or directory is refused, a symbolic link followed). Throws
// vxl::Error (Output) naming `path` when it cannot be written, std::runtime_error for a malformed image.
void write_png(const std::string& path, int w, int h, const std::vector<std::uint8_t>& rgba);
inline void write_png(const std::string& path, const Image& img) { write_png(path, img.width, img.height, img.rgba); }

// The picture format a path's extension names (case-insensitive): "png" (.png, or no extension), "jpeg"
// (.jpg, .jpeg; no alpha: the alpha channel is dropped), "tiff" (.tif, .tiff) or "openexr" (.exr, half
// floats); empty for any other.
std::string picture_format_of(const std::string& path);
// "PNG (.png), JPEG (.jpg, .jpeg), TIFF (.tif, .tiff) or OpenEXR (.exr)", for messages and help texts, from the
// same table as picture_format_of.
std::string picture_formats_text();
// As write_png, in the format the extension names. Throws vxl::Error (Usage) for an extension that names none.
void write_picture(const std::string& path, int w, int h, const std::vector<std::uint8_t>& rgba);

// Reads any format OpenImageIO knows (first subimage) as RGBA8: grey -> RGB, missing alpha -> 255,
// extra channels dropped, other bit depths converted. Throws std::runtime_error naming `path`.
Image read_image(const std::string& path);

// ImageBufAlgo::compare over all four channels, values on a 0..1 scale.
struct ImageDiff {
  double mean_error = 0;  // mean absolute error over all channel values
  double rms_error = 0;
  double psnr = 0;  // dB; +inf when identical
  double max_error = 0;
  int max_x = 0, max_y = 0, max_channel = 0;  // where max_error occurred (y counted from the top)
  std::uint64_t differing_pixels = 0;         // pixels with any channel different
};

// Throws std::runtime_error when sizes differ or the buffers are malformed.
ImageDiff compare_images(const Image& a, const Image& b);

}  // namespace vxl
