// Typed errors of the library. apps/ maps them to exit codes:
//   InputError, UsageError, ResourceError -> one line on stderr, exit 2
//   anything else                         -> "internal error", exit 1
// Throw at the boundary (readers, config parsing, argument checks) with a
// message that names the file or field and what is wrong; never print and return.
#pragma once
#include <stdexcept>
#include <string>

namespace tg {

// Bad input data: a file that cannot be read, a wrong header, NaN where none is
// allowed, an out-of-range parameter. what() = "FILE: problem".
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A request that cannot be honoured on this machine (not enough memory, a
// size whose voxel count overflows 64 bits).
struct ResourceError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Inconsistent arguments from a caller (CLI or API).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace tg
