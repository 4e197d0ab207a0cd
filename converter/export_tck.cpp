#include "export_tck.h"

#include <filesystem>

#include "tck_writer.h"
#include "vxl_streamlines.h"

namespace vxl {

void export_tck(const VxlFile& file, const std::string& out_path) {
  TckWriter writer(out_path, file.meta().streamline_count, {"voxlines_exported_from: " + std::filesystem::path(file.path()).filename().string()});
  WalkCallbacks cb;
  cb.streamline = [&](std::uint64_t, std::span<const float> xyz) { writer.add(xyz); };
  walk_streamlines(file, cb);
  writer.finish();
}

}  // namespace vxl
