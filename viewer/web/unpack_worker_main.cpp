// The web page's unpacker of .vxlz packages, a WebAssembly module of its own run in a Web Worker
// (page/unpack_worker.js): a module without threads runs on the thread that calls it, so the page's viewer module
// would freeze the page for the whole unpack (seconds for a large package); this one runs beside it, and the worker
// is ended with it, its memory with it. The unpack is the viewer module's (web_package.h): `voxlines unpack`'s code.
#include <emscripten/emscripten.h>

#include <cstdint>
#include <exception>
#include <optional>
#include <string>

#include "viewer/web/web_package.h"

namespace {

std::optional<vxl::MappedFile>& unpacked() {
  static std::optional<vxl::MappedFile> file;
  return file;
}

std::string& last_error() {
  static std::string error;
  return error;
}

}  // namespace

extern "C" {

// Unpacks the package `bytes` (from malloc, `size` bytes, named `name` in errors; freed here) into a .vxl held by
// the module until the next call: 1, and vu_data / vu_size give it; 0, and vu_error says why.
EMSCRIPTEN_KEEPALIVE int vu_unpack(std::uint8_t* bytes, double size, const char* name) {
  unpacked().reset();
  last_error().clear();
  try {
    unpacked().emplace(
        vxl::web::unpack_package(vxl::MappedFile::adopt(name, bytes, static_cast<std::size_t>(size)), name));
    return 1;
  } catch (const std::exception& e) {
    last_error() = e.what();
    return 0;
  }
}

EMSCRIPTEN_KEEPALIVE const std::uint8_t* vu_data() { return unpacked() ? unpacked()->data() : nullptr; }
EMSCRIPTEN_KEEPALIVE double vu_size() { return unpacked() ? static_cast<double>(unpacked()->size()) : 0.0; }
EMSCRIPTEN_KEEPALIVE const char* vu_error() { return last_error().c_str(); }

}  // extern "C"
