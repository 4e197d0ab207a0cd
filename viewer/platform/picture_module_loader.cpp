#include "viewer/platform/picture_module_loader.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <vector>

#include "format/base/error.h"

namespace vxl::pictures {

namespace {

namespace fs = std::filesystem;

constexpr const char* kModuleName = "libvoxlines_pictures.so";

std::vector<std::string> places() {
  if (const char* chosen = std::getenv("VOXLINES_PICTURE_MODULE"); chosen != nullptr && *chosen != '\0')
    return {chosen};
  std::vector<std::string> list;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    list.push_back((exe.parent_path() / kModuleName).string());
    list.push_back((exe.parent_path() / VOXLINES_PICTURE_MODULE_INSTALLED / kModuleName).lexically_normal().string());
  }
  list.push_back(VOXLINES_PICTURE_MODULE_BUILT);
  return list;
}

struct Loaded {
  const Api* api = nullptr;
  std::string tried;  // each place and why it failed, for the error
};

Loaded load() {
  Loaded loaded;
  for (const std::string& place : places()) {
    // RTLD_LOCAL: OpenImageIO's symbols stay out of the program's namespace. Never closed: the module's
    // libraries keep state until exit.
    void* handle = ::dlopen(place.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* why = ::dlerror();
      loaded.tried += "\n  " + (why ? std::string(why) : place + ": not loaded");
      continue;
    }
    using Entry = const Api* (*)();
    auto entry = reinterpret_cast<Entry>(::dlsym(handle, kVoxlinesPictureApiSymbol));
    const Api* api = entry ? entry() : nullptr;
    if (api == nullptr || api->abi_version != kAbiVersion) {
      loaded.tried += "\n  " + place + ": not this build's picture module (version " +
                      (api ? std::to_string(api->abi_version) : std::string("unknown")) + ", expected " +
                      std::to_string(kAbiVersion) + ")";
      continue;
    }
    loaded.api = api;
    return loaded;
  }
  return loaded;
}

}  // namespace

const Api& picture_module(const std::string& picture) {
  static std::once_flag once;
  static Loaded loaded;
  std::call_once(once, [] { loaded = load(); });
  if (loaded.api == nullptr)
    throw Error(ErrorKind::Unsupported, picture, std::nullopt,
                std::string("pictures need the picture module ") + kModuleName +
                    " (OpenImageIO), which could not be loaded; tried:" + loaded.tried);
  return *loaded.api;
}

}  // namespace vxl::pictures
