#include "viewer/web/web_package.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>

#include "converter/package/unpack.h"
#include "format/base/error.h"
#include "format/vxlz_layout.h"
#include "format/vxlz_package.h"

namespace vxl::web {

// What a package's decoded positions may take (UnpackSettings::memory_limit): the page's memory holds the .vxl
// beside them, and the tab the page's copy of it. The 1M set's whole (768 MB of floats for a 781 MB .vxl) is decoded
// twice instead.
constexpr std::uint64_t kDecodedPositionsBytes = std::uint64_t(256) << 20;
// A look's (a level alone's), which come on top of the package arriving in the same memory: the unpacker's memory
// never shrinks, and the 1M set's level 1 kept as floats (96 MB) raised it past what the whole then needs (298 MiB
// against 247). Its coarser looks keep theirs (level 3: 1.3 MB).
constexpr std::uint64_t kLookDecodedPositionsBytes = std::uint64_t(16) << 20;
namespace {

// Removes a file of the in-memory file system when it goes out of scope: its bytes are the page's memory.
struct RemovedAtExit {
  std::string path;
  ~RemovedAtExit() { std::remove(path.c_str()); }
};

// A copy of `bytes` in memory of its own (MappedFile::adopt's), named `name` in errors.
MappedFile copy_of(std::span<const std::uint8_t> bytes, const std::string& name) {
  auto* copy = static_cast<std::uint8_t*>(std::malloc(std::max<std::size_t>(bytes.size(), 1)));
  if (copy == nullptr) throw Error(ErrorKind::Unsupported, name, std::nullopt, "no memory to unpack this package in");
  std::memcpy(copy, bytes.data(), bytes.size());
  return MappedFile::adopt(name, copy, bytes.size());
}

}  // namespace

bool is_package(std::span<const std::uint8_t> bytes) {
  return bytes.size() >= kVxlzMagic.size() && std::equal(kVxlzMagic.begin(), kVxlzMagic.end(), bytes.begin());
}

std::string package_name(const std::string& name) {
  const std::string leaf = std::filesystem::path(name).filename().string();
  return leaf.empty() || leaf == "." || leaf == ".." ? "package.vxlz" : leaf;
}

std::string unpack_package_to_file(MappedFile package_bytes, const std::string& name) {
  const std::string unpacked = package_name(name) + ".vxl";
  UnpackSettings settings;
  settings.threads = 1;  // this WebAssembly build has no threads
  settings.memory_limit = kDecodedPositionsBytes;
  // The .vxl's pieces lie beside the unpacker's memory, which never shrinks: VERT held whole there would sit in the tab
  // twice once the file is complete (256 MB for 1M streamlines).
  settings.vertex_blocks = true;
  unpack_vxlz(VxlzFile::open(std::move(package_bytes)), unpacked, settings);
  return unpacked;
}

MappedFile unpack_package(MappedFile package, const std::string& name) {
  const RemovedAtExit unpacked{unpack_package_to_file(std::move(package), name)};
  return MappedFile(unpacked.path);
}

std::optional<std::vector<Look>> plan_looks(std::span<const std::uint8_t> prefix, const std::string& name,
                                            std::uint64_t max_points) {
  // Everything before the positions is what opening the prefix needs.
  const std::optional<std::uint64_t> positions = VxlzFile::positions_offset(prefix);
  if (positions && *positions == 0) return std::vector<Look>();  // no positions: nothing to look at
  if (!positions || prefix.size() < *positions) return std::nullopt;
  try {
    const VxlzFile f = VxlzFile::open_prefix(copy_of(prefix.first(*positions), package_name(name)));
    std::vector<Look> looks;
    for (const ShippedLevel& l : shipped_levels(f)) {  // coarsest first
      if (l.level == 0 || l.points == 0) continue;     // nothing to look at
      if (l.points <= max_points)
        looks = {{l.level, l.bytes}};  // the finest still this small looks first
      else if (!looks.empty())
        looks.push_back({l.level, l.bytes});  // the finer ones after it
    }
    return looks;
  } catch (const std::exception&) {  // refused, or no memory for its tables: the whole package's unpack says why
    return std::vector<Look>();
  }
}

std::string unpack_level_to_file(std::span<const std::uint8_t> prefix, std::uint32_t level, const std::string& name) {
  const std::string unpacked = package_name(name) + ".level.vxl";
  UnpackSettings settings;
  settings.threads = 1;
  settings.memory_limit = kLookDecodedPositionsBytes;
  settings.level = level;
  unpack_vxlz(VxlzFile::open_prefix(copy_of(prefix, package_name(name))), unpacked, settings);
  return unpacked;
}

}  // namespace vxl::web
