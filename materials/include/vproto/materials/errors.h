#pragma once
// The three levels of failure (STYLE.md "Errors"): bad user input, a simulation that
// cannot go on, and broken internal invariants.

#include <stdexcept>
#include <string>

namespace vproto {

/// A place in a source file; line and column are 1-based, 0 when unknown.
struct SourceLoc {
  std::string file;
  int line = 0;
  int column = 0;
};

/// Bad user input (script, file, flag). Rendered as `FILE:LINE:COL: error: MESSAGE`;
/// the CLI turns it into exit code 2.
class InputError : public std::runtime_error {
 public:
  InputError(SourceLoc loc, const std::string& message);
  explicit InputError(const std::string& message) : InputError(SourceLoc{}, message) {}
  const SourceLoc& loc() const { return loc_; }
  const std::string& message() const { return message_; }

 private:
  SourceLoc loc_;
  std::string message_;
};

/// A simulation that cannot go on (non-finite state, singular system); exit code 3.
class SimulationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A broken internal invariant; exit code 1.
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

[[noreturn]] void demand_failed(const char* condition, const char* file, int line);

}  // namespace vproto

/// Checked in every build type.
#define VPROTO_DEMAND(cond) \
  ((cond) ? static_cast<void>(0) : ::vproto::demand_failed(#cond, __FILE__, __LINE__))

#ifdef NDEBUG
#define VPROTO_ASSERT(cond) static_cast<void>(0)
#else
#define VPROTO_ASSERT(cond) VPROTO_DEMAND(cond)
#endif
