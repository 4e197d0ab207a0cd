// One error type for the whole project: it names the file, the byte offset when one is known, and
// what was expected, and carries a kind that the command-line drivers turn into a distinct exit code.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace vxl {

// Exit codes of the command-line programs (0 is success, 1 is "verify found the file invalid").
enum class ErrorKind : int {
  Usage = 2,        // wrong command line
  Input = 3,        // malformed or unreadable input file
  Unsupported = 4,  // valid input we do not handle (format, feature, size beyond a limit)
  Output = 5,       // cannot write the output
};

// The exit code of an unexpected exception (a bug rather than a bad input): EX_SOFTWARE of sysexits.h.
inline constexpr int kExitInternalError = 70;

class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, std::string file, std::optional<std::uint64_t> offset, const std::string& what)
      : std::runtime_error(compose(file, offset, what)),
        kind_(kind),
        file_(std::move(file)),
        offset_(offset),
        reason_(what) {}

  ErrorKind kind() const { return kind_; }
  const std::string& file() const { return file_; }
  std::optional<std::uint64_t> offset() const { return offset_; }
  const std::string& reason() const { return reason_; }

 private:
  static std::string compose(const std::string& file, std::optional<std::uint64_t> offset, const std::string& what) {
    // An error about no file in particular (a command-line option) says only what is wrong.
    std::string m = file;
    if (offset) m += (m.empty() ? "at byte " : ": at byte ") + std::to_string(*offset);
    return m.empty() ? what : m + ": " + what;
  }

  ErrorKind kind_;
  std::string file_;
  std::optional<std::uint64_t> offset_;
  std::string reason_;
};

// Shorthands: throw an error about bad input data / an unsupported feature.
[[noreturn]] inline void fail_input(const std::string& file, std::optional<std::uint64_t> offset,
                                    const std::string& what) {
  throw Error(ErrorKind::Input, file, offset, what);
}
[[noreturn]] inline void fail_unsupported(const std::string& file, const std::string& what) {
  throw Error(ErrorKind::Unsupported, file, std::nullopt, what);
}

}  // namespace vxl
