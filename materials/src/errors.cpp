#include "vproto/materials/errors.h"

namespace vproto {
namespace {

std::string format_input_error(const SourceLoc& loc, const std::string& message) {
  std::string out;
  if (!loc.file.empty()) {
    out += loc.file;
    if (loc.line > 0) out += ":" + std::to_string(loc.line) + ":" + std::to_string(loc.column);
    out += ": ";
  }
  return out + "error: " + message;
}

}  // namespace

InputError::InputError(SourceLoc loc, const std::string& message)
    : std::runtime_error(format_input_error(loc, message)),
      loc_(std::move(loc)),
      message_(message) {}

void demand_failed(const char* condition, const char* file, int line) {
  throw InternalError(std::string("internal invariant failed: ") + condition + " at " + file + ":" +
                      std::to_string(line));
}

}  // namespace vproto
