#include "converter/pipeline/memory_budget.h"

#include <optional>

#include "format/base/error.h"
#include "format/base/memory_size.h"

namespace vxl {

void MemoryBudget::fail(std::uint64_t needs, std::uint64_t others, const std::string& what,
                        const std::string& hint) const {
  // A quarter more than the sum, for what comes later.
  const std::uint64_t suggested = (needs + others) / 4 * 5;
  throw MemoryLimitTooSmall(
      path_,
      "--memory-limit " + format_memory_size(limit_) + " is too small: " + what + " needs " +
          format_memory_size(needs) +
          (others > 0 ? " on top of " + format_memory_size(others) + " already taken" : std::string()) +
          "; use --memory-limit " + memory_limit_argument(suggested) + " or more" + hint,
      suggested);
}

}  // namespace vxl
