// `voxlines share`: a folder that any static web server serves as it is, for people without voxview: the web
// viewer (viewer/web: the project's reader and renderer in WebAssembly, drawing with WebGL2), the tractogram
// as given (a .vxl, which the page fetches by ranges, or a .vxlz, which it fetches whole and unpacks; or the .vxlz
// unpacked here into a .vxl), share.json naming it, and a README for the recipient.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "format/vxl_fetch_plan.h"

namespace vxl {

struct ShareSettings {
  std::string title;           // shown by the page; empty: the file's name
  std::string web_viewer_dir;  // the built web viewer (index.html, viewer.js, voxweb.js, voxweb.wasm)
  // A .vxlz: unpacked into a .vxl in the folder (8 times larger to host, but a large one then shows its first
  // picture before the whole file is in), else copied as it is.
  bool unpack = false;
  unsigned threads = 0;  // for unpacking a .vxlz (0: all cores)
  // Only the streamlines of this level of detail (about 1/8^level of them, alike everywhere), as a .vxl: a
  // tractogram too large for a browser's memory made small enough (a .vxlz is unpacked first).
  std::optional<std::uint32_t> level;
  // The most of a .vxl the web viewer holds in WebAssembly's memory: a larger one is drawn from the coarser levels of
  // detail that fit (a level image, format/vxl_level_image.h), fetched by ranges; a package, unpacked whole in the
  // page, must fit.
  std::uint64_t max_data_bytes = kWebMaxFileBytes;
};

struct ShareSummary {
  std::string data_file;  // the tractogram's name in the folder
  std::uint64_t data_bytes = 0;
  std::uint64_t streamlines = 0;
  bool package = false;   // the folder holds a .vxlz
  bool unpacked = false;  // the input was a .vxlz, unpacked (ShareSettings::unpack)
  // The shared .vxl is larger than the page holds: it draws this level of detail and the coarser ones (a level image).
  std::optional<std::uint32_t> image_level;
};

// The files of the built web viewer that a shared folder holds.
inline constexpr const char* kWebViewerFiles[] = {"index.html",       "viewer.js",    "voxweb.js",     "voxweb.wasm",
                                                  "unpack_worker.js", "voxunpack.js", "voxunpack.wasm"};

// Writes the folder `out_dir`, which must not exist: made under a temporary name beside it and renamed
// when complete, so that a failure or an interruption leaves no partial folder at `out_dir`. Throws
// vxl::Error: Input for a damaged input, Unsupported when there is no web viewer, a package's .vxl would be larger
// than `max_data_bytes` (the message names the --level that would fit), or not even a .vxl's coarsest level fits it,
// Output when the folder cannot be written.
ShareSummary share_folder(const std::string& in_path, const std::string& out_dir, const ShareSettings& settings);

}  // namespace vxl
