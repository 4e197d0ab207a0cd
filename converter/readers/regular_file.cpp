#include "converter/readers/regular_file.h"

#include <sys/stat.h>

#include "format/base/error.h"

namespace vxl {

void require_regular_file(const std::string& path, bool allow_directory) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return;
  if (S_ISREG(st.st_mode) || (allow_directory && S_ISDIR(st.st_mode))) return;
  const char* what = S_ISFIFO(st.st_mode)                         ? "a FIFO"
                     : S_ISDIR(st.st_mode)                        ? "a directory"
                     : S_ISSOCK(st.st_mode)                       ? "a socket"
                     : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device"
                                                                  : "something else than a regular file";
  fail_input(path, std::nullopt,
             std::string("is ") + what +
                 (allow_directory ? "; expected a regular file or a TRX directory" : "; expected a regular file"));
}

}  // namespace vxl
