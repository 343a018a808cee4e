#include "phex/error.hpp"

#include "phex/progress.hpp"

namespace phex {

const char* errorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidParameter: return "invalid_parameter";
    case ErrorCode::InvalidInput: return "invalid_input";
    case ErrorCode::CannotTile: return "cannot_tile";
    case ErrorCode::Cancelled: return "cancelled";
    case ErrorCode::Io: return "io";
    case ErrorCode::Internal: return "internal";
  }
  return "internal";
}

void checkCancel(const CancelFlag* cancel) {
  if (cancel && cancel->load(std::memory_order_relaxed)) throw Error(ErrorCode::Cancelled, "cancelled by the caller");
}

}  // namespace phex
