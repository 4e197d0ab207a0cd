#include "format/base/output_path.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include <sys/stat.h>

#include "format/base/error.h"

namespace vxl {
namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

}  // namespace

std::string output_target(const std::string& path) {
  namespace fs = std::filesystem;
  fs::path target(path);
  // As many links as the kernel follows in a path (MAXSYMLINKS).
  for (int hops = 0; hops <= 40; ++hops) {
    struct stat st;
    if (::lstat(target.c_str(), &st) != 0) {
      if (errno != ENOENT && errno != ENOTDIR)
        throw Error(ErrorKind::Output, path, std::nullopt, std::string("cannot stat: ") + std::strerror(errno));
      // To be created: its folder must be there.
      const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
      struct stat fst;
      if (::stat(folder.c_str(), &fst) != 0)
        throw Error(ErrorKind::Output, path, std::nullopt,
                    "cannot write into the folder " + folder.string() + ": " + std::strerror(errno));
      if (!S_ISDIR(fst.st_mode))
        throw Error(ErrorKind::Output, path, std::nullopt, folder.string() + " is not a folder");
      return target.string();
    }
    if (S_ISREG(st.st_mode)) return target.string();
    if (!S_ISLNK(st.st_mode)) {
      const std::string what =
          target.string() == path ? "" : " (where the symbolic link leads, " + target.string() + ")";
      throw Error(ErrorKind::Output, path, std::nullopt,
                  std::string("is ") + kind_of(st.st_mode) + what +
                      ": an output is written only as a regular file, and never replaces anything else");
    }
    std::error_code ec;
    const fs::path next = fs::read_symlink(target, ec);
    if (ec) throw Error(ErrorKind::Output, path, std::nullopt, "cannot read the symbolic link: " + ec.message());
    target = next.is_absolute() ? next : target.parent_path() / next;
  }
  throw Error(ErrorKind::Output, path, std::nullopt, "too many levels of symbolic links");
}

bool same_output(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  const std::string ta = output_target(a), tb = output_target(b);
  struct stat sa, sb;
  if (::stat(ta.c_str(), &sa) == 0 && ::stat(tb.c_str(), &sb) == 0)
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  std::error_code ea, eb;
  const fs::path ca = fs::weakly_canonical(ta, ea), cb = fs::weakly_canonical(tb, eb);
  return !ea && !eb ? ca == cb : fs::absolute(ta).lexically_normal() == fs::absolute(tb).lexically_normal();
}

std::filesystem::path temporary_folder() {
  const char* tmpdir = std::getenv("TMPDIR");
  if (!tmpdir || !*tmpdir) return "/tmp";
  std::error_code ec;
  if (!std::filesystem::is_directory(tmpdir, ec))
    throw Error(ErrorKind::Output, std::string("TMPDIR=") + tmpdir, std::nullopt,
                "names no folder for temporary files: set TMPDIR to an existing folder, or unset it to use /tmp");
  return tmpdir;
}

}  // namespace vxl
