// The web page's unpacker of .vxlz packages, a WebAssembly module of its own run in a Web Worker
// (page/unpack_worker.js): a module without threads runs on the thread that calls it, so the page's viewer module
// would freeze the page for the whole unpack (seconds for a large package); this one runs beside it, and the worker
// is ended with it, its memory with it. The unpack is the viewer module's (web_package.h): `voxlines unpack`'s code.
//
// A package is handed over as it arrives (vu_begin, then its pieces written where vu_begin said, vu_arrived after
// each): once the first bytes hold a level of detail small enough for a first look (a package of a file with levels
// ships its coarsest level first), vu_arrived asks for it, vu_unpack_level unpacks it alone, and the page shows it
// while the rest arrives, and the finer levels (vu_looks) the page asks for while the rest is still far off; vu_unpack
// then unpacks the whole. Each .vxl is written into the module's current folder, whose files are kept in pieces
// (unpack_pieces_fs.js), and the script hands the pieces to the page as they are (vu_unpacked names the file).
#include <emscripten/emscripten.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "viewer/app/frame_budget.h"
#include "viewer/web/web_package.h"

namespace {

// The .vxl the last unpack wrote into the in-memory file system: the worker's script hands its pieces over as they
// lie there (no copy in the module's memory) and removes it.
std::string& unpacked() {
  static std::string path;
  return path;
}

std::string& last_error() {
  static std::string error;
  return error;
}

// The package arriving: its bytes so far, and the first look planned once its tables are in.
struct Arriving {
  std::uint8_t* bytes = nullptr;  // malloc'd, the package's declared size
  std::uint64_t size = 0, received = 0;
  std::string name;
  std::optional<std::vector<vxl::web::Look>> looks;  // planned once the tables are in (plan_looks)
  bool first_look_asked = false;
};

Arriving& arriving() {
  static Arriving a;
  return a;
}

// Runs `unpack` (which sets unpacked()): 1, or 0 with vu_error saying why.
template <typename Fn>
int answer(Fn&& unpack) {
  unpacked().clear();
  last_error().clear();
  try {
    unpack();
    return 1;
  } catch (const std::exception& e) {
    last_error() = e.what();
    return 0;
  }
}

}  // namespace

extern "C" {

// A package of `size` bytes, named `name` in errors, is about to arrive: where to write its bytes (null: no memory).
EMSCRIPTEN_KEEPALIVE std::uint8_t* vu_begin(double size, const char* name) {
  Arriving& a = arriving();
  std::free(a.bytes);
  a = Arriving();
  a.size = static_cast<std::uint64_t>(size);
  a.name = name;
  a.bytes = static_cast<std::uint8_t*>(std::malloc(a.size > 0 ? a.size : 1));
  return a.bytes;
}

// The package is longer than it said (a body whose length was not the one declared): room for `size` bytes, keeping
// those in; null when there is no memory for them.
EMSCRIPTEN_KEEPALIVE std::uint8_t* vu_grow(double size) {
  Arriving& a = arriving();
  auto* grown = static_cast<std::uint8_t*>(std::realloc(a.bytes, static_cast<std::size_t>(size)));
  if (grown != nullptr) {
    a.bytes = grown;
    a.size = static_cast<std::uint64_t>(size);
  }
  return grown;
}

// The package's first `received` bytes are in: the level of its first look when its bytes have just become complete
// (vu_unpack_level then unpacks it), else 0.
EMSCRIPTEN_KEEPALIVE int vu_arrived(double received) {
  Arriving& a = arriving();
  a.received = static_cast<std::uint64_t>(received);
  if (!a.looks)
    a.looks = vxl::web::plan_looks({a.bytes, static_cast<std::size_t>(a.received)}, a.name,
                                   vxl::app::kFirstPictureSegments);  // points: about as many segments
  if (!a.looks || a.looks->empty() || a.first_look_asked || a.received < a.looks->front().bytes) return 0;
  a.first_look_asked = true;
  return static_cast<int>(a.looks->front().level);
}

// The looks planned (JSON [[level, bytes], ...], coarsest first; [] for none, or while the tables are not in): the
// page asks for the finer ones (vu_unpack_level) while the rest of the package is still far off.
EMSCRIPTEN_KEEPALIVE const char* vu_looks() {
  static std::string text;
  text = "[";
  for (const vxl::web::Look& l : arriving().looks.value_or(std::vector<vxl::web::Look>()))
    text += (text.size() > 1 ? "," : "") + ("[" + std::to_string(l.level) + "," + std::to_string(l.bytes) + "]");
  text += "]";
  return text.c_str();
}

// Unpacks look `level` (one of vu_looks') from the bytes in: 1, and vu_unpacked names its .vxl; 0, and vu_error says
// why (also when its bytes are not all in).
EMSCRIPTEN_KEEPALIVE int vu_unpack_level(int level) {
  const Arriving& a = arriving();
  return answer([&] {
    const std::vector<vxl::web::Look> none;
    const auto& looks = a.looks ? *a.looks : none;
    const auto look = std::find_if(looks.begin(), looks.end(), [&](const auto& l) { return int(l.level) == level; });
    if (look == looks.end() || look->bytes > a.received || a.bytes == nullptr)
      throw std::runtime_error(a.name + ": level " + std::to_string(level) + " of the package is not in yet");
    unpacked() = vxl::web::unpack_level_to_file({a.bytes, static_cast<std::size_t>(look->bytes)}, look->level, a.name);
  });
}

// Unpacks the whole package, once all of it is in (its bytes are let go): 1, and vu_unpacked names the .vxl; 0, and
// vu_error says why.
EMSCRIPTEN_KEEPALIVE int vu_unpack() {
  Arriving& a = arriving();
  std::uint8_t* bytes = std::exchange(a.bytes, nullptr);  // no look after this: their bytes go with the package's
  a.looks.reset();
  return answer([&] {
    unpacked() = vxl::web::unpack_package_to_file(
        vxl::MappedFile::adopt(vxl::web::package_name(a.name), bytes, static_cast<std::size_t>(a.received)), a.name);
  });
}

// The path of the .vxl the last unpack wrote in the in-memory file system (empty after a failure).
EMSCRIPTEN_KEEPALIVE const char* vu_unpacked() { return unpacked().c_str(); }
EMSCRIPTEN_KEEPALIVE const char* vu_error() { return last_error().c_str(); }

}  // extern "C"
