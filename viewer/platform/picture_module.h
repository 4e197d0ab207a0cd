// The picture module's interface: what image_io.cpp asks of OpenImageIO, behind one table of functions that
// libvoxlines_pictures.so (picture_module.cpp) exports and picture_module_loader.cpp loads with dlopen the
// first time a TIFF or OpenEXR picture is written or any picture read or compared.
//
// Why a module: OpenImageIO pulls in some 250 shared libraries, and linking them costs every start of a
// program that links it about half a second (more on a cold disk), whether it writes a picture or not. The
// viewer writes PNG and JPEG without it (stb_image_write), so only the other formats, the tests' reading and
// the benchmarks' comparisons pay for it.
//
// Both sides are built together by this project (same compiler, same standard library), so the table passes
// C++ types; no exception crosses it: every function reports failure through its return value and `error`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace vxl::pictures {

// Raised whenever the table changes; the loader refuses a module of another version.
inline constexpr std::uint32_t kAbiVersion = 1;

enum class WriteStatus {
  Ok,
  NoWriter,     // OpenImageIO has no writer for the format (a bug or a broken installation)
  OutputFailed  // the file cannot be opened, written or finished (a missing folder, a full disk)
};

// ImageBufAlgo::compare's results, values on OpenImageIO's 0..1 scale.
struct Comparison {
  double mean_error = 0, rms_error = 0, psnr = 0, max_error = 0;
  int max_x = 0, max_y = 0, max_channel = 0;
  std::uint64_t failing_pixels = 0, warning_pixels = 0;
};

struct Api {
  std::uint32_t abi_version;
  // Writes w x h RGBA8 pixels (rows top to bottom, straight alpha) to `path` as OpenImageIO's `format`
  // ("png", "jpeg": colour only, "tiff", "openexr": half floats), exactly these bytes for the 8-bit formats.
  WriteStatus (*write)(const char* format, const char* path, int w, int h, const std::uint8_t* rgba,
                       std::string& error) noexcept;
  // Reads the first subimage of any format OpenImageIO knows as RGBA8 (grey -> RGB, missing alpha -> 255,
  // other depths converted, the file's straight alpha kept). False with `error` set when it cannot.
  bool (*read)(const char* path, int& w, int& h, std::vector<std::uint8_t>& rgba, std::string& error) noexcept;
  // ImageBufAlgo::compare of two w x h RGBA8 images over channels [0, channels), with its fail and warn
  // thresholds. False with `error` set when the comparison itself failed.
  bool (*compare)(int w, int h, const std::uint8_t* a, const std::uint8_t* b, int channels, float fail_threshold,
                  float warn_threshold, Comparison& result, std::string& error) noexcept;
};

}  // namespace vxl::pictures

// The module's one exported symbol.
extern "C" const vxl::pictures::Api* voxlines_picture_api();
inline constexpr const char* kVoxlinesPictureApiSymbol = "voxlines_picture_api";
