#include "viewer/web/web_package.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "converter/package/unpack.h"
#include "format/base/error.h"
#include "format/vxlz_layout.h"

namespace vxl::web {
namespace {

// Removes a file of the in-memory file system when it goes out of scope: its bytes are the page's memory.
struct RemovedAtExit {
  std::string path;
  ~RemovedAtExit() { std::remove(path.c_str()); }
};

// The name the package has in the file system (and so in errors): the page's name for it, less any folder.
std::string package_path(const std::string& name) {
  const std::string leaf = std::filesystem::path(name).filename().string();
  return leaf.empty() || leaf == "." || leaf == ".." ? "package.vxlz" : leaf;
}

}  // namespace

bool is_package(std::span<const std::uint8_t> bytes) {
  return bytes.size() >= kVxlzMagic.size() && std::equal(kVxlzMagic.begin(), kVxlzMagic.end(), bytes.begin());
}

MappedFile unpack_package(MappedFile package_bytes, const std::string& name) {
  const RemovedAtExit package{package_path(name)}, unpacked{package.path + ".vxl"};
  std::FILE* f = std::fopen(package.path.c_str(), "wb");
  const std::span<const std::uint8_t> bytes = package_bytes.bytes();
  const bool written = f != nullptr && std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  if (f == nullptr || std::fclose(f) != 0 || !written)
    throw Error(ErrorKind::Unsupported, name, std::nullopt, "no memory to unpack this package in");
  { const MappedFile released = std::move(package_bytes); }  // the file system's copy is the one unpacked
  UnpackSettings settings;
  settings.threads = 1;  // this WebAssembly build has no threads
  unpack_vxlz(package.path, unpacked.path, settings);
  std::remove(package.path.c_str());  // before the .vxl is read into memory: the page holds one file at a time
  return MappedFile(unpacked.path);
}

}  // namespace vxl::web
