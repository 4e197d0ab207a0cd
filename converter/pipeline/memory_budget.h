// The memory a conversion within --memory-limit holds, counted against the limit. Every buffer the
// conversion takes is taken here first, so that a limit too small for some part of the work is refused
// before that part runs, with a message naming the part, what it needs and a limit that would do.
#pragma once

#include <cstdint>
#include <string>

#include "format/base/error.h"

namespace vxl {

// A limit too small for some part of the work (Unsupported), with the limit the message suggests.
class MemoryLimitTooSmall : public Error {
 public:
  MemoryLimitTooSmall(const std::string& path, const std::string& what, std::uint64_t suggested)
      : Error(ErrorKind::Unsupported, path, std::nullopt, what), suggested_(suggested) {}
  std::uint64_t suggested() const { return suggested_; }

 private:
  std::uint64_t suggested_;
};

class MemoryBudget {
 public:
  // `path` names the source in the errors.
  MemoryBudget(std::uint64_t limit, std::string path) : limit_(limit), path_(std::move(path)) {}
  std::uint64_t limit() const { return limit_; }
  std::uint64_t used() const { return used_; }
  std::uint64_t left() const { return used_ < limit_ ? limit_ - used_ : 0; }
  // Takes `bytes` more, or throws Unsupported naming `what` (a singular noun phrase), what it needs and a
  // limit that would do; `hint` is appended to the message.
  void take(std::uint64_t bytes, const std::string& what, const std::string& hint = "") {
    if (bytes > left()) fail(bytes, used_, what, hint);
    used_ += bytes;
  }
  // Follows a buffer that grows to `bytes`: takes its growth since `held`, which it updates. what() names it
  // (called only on failure: the name may be costly to make).
  template <typename What>
  void track(std::uint64_t bytes, std::uint64_t& held, What&& what, const std::string& hint = "") {
    if (bytes <= held) return;
    if (bytes - held > left()) fail(bytes, used_ - held, what(), hint);
    used_ += bytes - held;
    held = bytes;
  }
  // Gives back what a buffer followed by track() no longer holds once it is down to `bytes`.
  void shrink(std::uint64_t bytes, std::uint64_t& held) {
    if (bytes >= held) return;
    used_ -= held - bytes;
    held = bytes;
  }
  // Throws MemoryLimitTooSmall: `what` needs `needs` on top of `others`; suggests a quarter more than their sum.
  [[noreturn]] void fail(std::uint64_t needs, std::uint64_t others, const std::string& what,
                         const std::string& hint = "") const;

 private:
  std::uint64_t limit_;
  std::uint64_t used_ = 0;
  std::string path_;
};

}  // namespace vxl
