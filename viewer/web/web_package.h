// A .vxlz package opened in the web page: unpacked as `voxlines unpack` unpacks it (converter/package/unpack.h),
// through Emscripten's in-memory file system, into the .vxl bytes the viewer opens.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "format/base/mapped_file.h"

namespace vxl::web {

// Whether `bytes` begin as a .vxlz package does (its magic, spec/vxlz-package-v2.md §2.1).
bool is_package(std::span<const std::uint8_t> bytes);

// The name a package named `name` by the page has in errors and in the provenance of the .vxl unpacked from it: its
// last part ("package.vxlz" when it has none), as `voxlines unpack` names it.
std::string package_name(const std::string& name);

// Unpacks the package `package` (its bytes, named package_name(name)) into a .vxl in the in-memory file system, and
// lets the package's bytes go; returns the .vxl's path, which the caller removes. Nothing is left in the file system
// when the package is refused (vxl::Error, as unpack_vxlz throws it).
std::string unpack_package_to_file(MappedFile package, const std::string& name);
// The same, the .vxl read into memory and removed from the file system.
MappedFile unpack_package(MappedFile package, const std::string& name);

// A package arriving: the levels of detail to look at before the whole (its level order's, spec §5.1), each with the
// prefix of the package that holds it, coarsest first: the first look is the finest with at most `max_points`
// shipped points (about the segments voxview's first picture draws), the others each finer one down to level 1, for
// a page to ask for while the rest is still far off. Empty for a package in streamline order, or with no level small
// enough, or whose tables are refused (the whole package's unpack then says why).
struct Look {
  std::uint32_t level = 0;
  std::uint64_t bytes = 0;
};
// nullopt while `prefix` (the package's first bytes) does not hold its tables yet: ask again with more.
std::optional<std::vector<Look>> plan_looks(std::span<const std::uint8_t> prefix, const std::string& name,
                                            std::uint64_t max_points);

// The streamlines of level `level` alone (unpack_vxlz's UnpackSettings::level), from the package's first bytes
// (`prefix`, copied), as a .vxl in the in-memory file system, as unpack_package_to_file leaves it.
std::string unpack_level_to_file(std::span<const std::uint8_t> prefix, std::uint32_t level, const std::string& name);

}  // namespace vxl::web
