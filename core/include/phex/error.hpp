// phex — errors that name the problem.
#pragma once
#include <stdexcept>
#include <string>

namespace phex {

// What went wrong, in a word a caller can switch on (also the `code` of the JS PHexError).
enum class ErrorCode {
  InvalidParameter,  // a parameter is missing, not finite or out of its documented range
  InvalidInput,      // a malformed file or mesh (bad counts, NaN, non-manifold, empty ...)
  CannotTile,        // the method cannot produce a valid P-Hex mesh for this surface / choice
  Cancelled,         // the caller's cancel flag was raised
  Io,                // a file could not be opened, read or written
  Internal           // a bug in phex: please report it
};

const char* errorCodeName(ErrorCode code);

class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

}  // namespace phex
