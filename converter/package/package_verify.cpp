#include "converter/package/package_verify.h"

#include "converter/convert/temporary_vxl.h"
#include "converter/package/unpack.h"
#include "format/base/error.h"

namespace vxl {

VerifyResult verify_vxlz(const std::string& path) {
  try {
    const TemporaryVxl unpacked =
        open_through_temporary_vxl(path, [&](const std::string& out) { unpack_vxlz(path, out, UnpackSettings()); });
    return verify_vxl(unpacked.file);
  } catch (const Error& e) {
    return VerifyResult::refused(e);
  }
}

}  // namespace vxl
