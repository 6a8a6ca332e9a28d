#pragma once
// An elastic body's contact stage as a coroutine (C++20), so that the stages of several
// bodies can hand their rows to one solve: a stage suspends once it has decided whether its
// body would rest (kDecided: every member decides before any looks for rows, and the
// group's floating bodies rest together or not at all), where it wants its rows
// solved (kSolve), again where a pass ends (kPassEnd: whether the passes stop) and where its
// velocity jumps are applied (kJumpsApplied); the driver at the end of
// Dynamics::elastic_contact_stage answers each for all the stages of a group at once. A
// stage alone is answered at once, without suspending.

#include <Eigen/Core>
#include <chrono>
#include <coroutine>
#include <exception>
#include <utility>
#include <vector>

#include "delassus.h"
#include "vproto/sim/point_contact_solver.h"

namespace vproto::sim {

/// What a stage hands over at a suspension.
struct StageRequest {
  enum Kind { kNone, kDecided, kSolve, kPassEnd, kJumpsApplied } kind = kNone;
  // kSolve: its rows (free motion and friction; W is assembled for the group's rows at once
  // from the sides), where to start, how to solve; the answer goes to `solution`
  PointContactProblem* problem = nullptr;
  std::vector<RowSides>* sides = nullptr;
  const std::vector<FloatingSide>* floating = nullptr;
  const FrameMobility* mobility = nullptr;
  const Eigen::VectorXd* warm = nullptr;
  PointContactOptions options;
  PointContactSolution* solution = nullptr;
  int body = -1;                                  ///< the stage's body
  std::chrono::steady_clock::time_point started;  ///< when it began assembling them
  // kPassEnd: whether its own rows have settled; the answer, whether the passes end.
  // kDecided: whether its body would rest; the answer, whether the group rests
  bool settled = false, stop = false;
};

class StageTask {
 public:
  struct promise_type {
    StageRequest request;
    std::exception_ptr error;
    StageTask get_return_object() {
      return StageTask(std::coroutine_handle<promise_type>::from_promise(*this));
    }
    std::suspend_always initial_suspend() noexcept { return {}; }
    std::suspend_always final_suspend() noexcept { return {}; }
    void return_void() {}
    void unhandled_exception() { error = std::current_exception(); }
  };
  using Handle = std::coroutine_handle<promise_type>;

  StageTask() = default;
  explicit StageTask(Handle h) : handle_(h) {}
  StageTask(StageTask&& o) noexcept : handle_(std::exchange(o.handle_, {})) {}
  StageTask& operator=(StageTask&& o) noexcept {
    if (this != &o) {
      if (handle_) handle_.destroy();
      handle_ = std::exchange(o.handle_, {});
    }
    return *this;
  }
  StageTask(const StageTask&) = delete;
  StageTask& operator=(const StageTask&) = delete;
  ~StageTask() {
    if (handle_) handle_.destroy();
  }

  /// Runs the stage to its next request or its end; an exception it threw is rethrown.
  void resume() {
    handle_.promise().request.kind = StageRequest::kNone;
    handle_.resume();
    if (handle_.promise().error) std::rethrow_exception(handle_.promise().error);
  }
  bool done() const { return handle_.done(); }
  StageRequest& request() { return handle_.promise().request; }

 private:
  Handle handle_;
};

/// The awaitable of a request: a stage on its own (`alone`) is answered at once by `answer`;
/// in a group it suspends with the request for the driver, which answers it in place.
template <class Answer>
struct StageAwait {
  StageRequest request;
  bool alone;
  Answer answer;
  StageRequest* posted = nullptr;
  bool await_ready() {
    if (alone) answer(request);
    return alone;
  }
  void await_suspend(StageTask::Handle h) {
    h.promise().request = request;
    posted = &h.promise().request;
  }
  StageRequest await_resume() { return posted ? *posted : request; }
};

}  // namespace vproto::sim
