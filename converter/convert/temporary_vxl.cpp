#include "converter/convert/temporary_vxl.h"

#include <linux/magic.h>
#include <stdlib.h>
#include <sys/vfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "format/base/error.h"
#include "format/base/mapped_file.h"
#include "format/base/output_path.h"

namespace vxl {
namespace {

// A fresh, empty file "voxlines-XXXXXX-NAME.vxl" in `dir`.
std::string reserve(const std::string& name, const std::string& dir) {
  std::string base = name;
  while (base.size() > 1 && base.back() == '/') base.pop_back();  // a TRX directory given as "x.trx/"
  std::string path =
      (std::filesystem::path(dir) / ("voxlines-XXXXXX-" + std::filesystem::path(base).filename().string() + ".vxl"))
          .string();
  const int suffix = static_cast<int>(path.size() - path.rfind("XXXXXX") - 6);
  const int fd = ::mkstemps(path.data(), suffix);
  if (fd < 0)
    throw Error(ErrorKind::Output, dir, std::nullopt,
                std::string("cannot create a temporary .vxl for ") + name + ": " + std::strerror(errno));
  ::close(fd);
  return path;
}

bool on_tmpfs(const std::string& dir) {
  struct statfs fs {};
  return ::statfs(dir.c_str(), &fs) == 0 && fs.f_type == TMPFS_MAGIC;
}

}  // namespace

TemporaryVxl open_through_temporary_vxl(const std::string& name, const std::function<void(const std::string&)>& write,
                                        const std::string& dir_given) {
  const std::string dir = dir_given.empty() ? temporary_folder().string() : dir_given;
  const std::string path = reserve(name, dir);
  try {
    write(path);
    MappedFile bytes(path);
    bytes.name_as(name);  // the temporary name means nothing to the user (group names, errors): the source's does
    VxlFile file = VxlFile::open(std::move(bytes));
    std::filesystem::remove(path);  // the mapping keeps the data
    return {std::move(file), path, on_tmpfs(dir)};
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
    throw;
  }
}

}  // namespace vxl
