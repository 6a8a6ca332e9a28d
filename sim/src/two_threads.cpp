#include "two_threads.h"

#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

#include "blas_threads.h"
#include "vproto/sim/elastic_contact.h"
#include "vproto/sim/linear_solver.h"

namespace vproto::sim {

namespace {

class Helper {
 public:
  Helper() : thread_([this] { loop(); }) {}
  ~Helper() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  Helper(const Helper&) = delete;
  Helper& operator=(const Helper&) = delete;

  /// One caller at a time: false when another holds the helper.
  bool try_claim() { return claim_.try_lock(); }
  void release() { claim_.unlock(); }

  void start(const std::function<void()>* task) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      task_ = task;
      failed_ = nullptr;
      done_ = false;
    }
    wake_.notify_all();
  }
  /// Waits for the task; its exception, if any.
  std::exception_ptr wait() {
    std::unique_lock<std::mutex> lock(mutex_);
    finished_.wait(lock, [this] { return done_; });
    return failed_;
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [this] { return stop_ || task_ != nullptr; });
      if (stop_) return;
      const std::function<void()>* task = task_;
      task_ = nullptr;
      lock.unlock();
      std::exception_ptr failed;
      try {
        (*task)();
      } catch (...) {
        failed = std::current_exception();
      }
      lock.lock();
      failed_ = failed;
      done_ = true;
      finished_.notify_all();
    }
  }

  std::mutex claim_;
  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  const std::function<void()>* task_ = nullptr;
  std::exception_ptr failed_;
  bool done_ = true, stop_ = false;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace

int contact_threads() {
  // under mpirun the ranks take the cores
  static const int threads =
      std::thread::hardware_concurrency() >= 2 && launched_ranks() <= 1 ? 2 : 1;
  return threads;
}

void in_two_threads(bool wanted, const std::function<void(int first, int stride)>& f) {
  if (!wanted || contact_threads() < 2) {
    f(0, 1);
    return;
  }
  static Helper helper;
  if (!helper.try_claim()) {
    f(0, 1);
    return;
  }
  const OneBlasThread one_blas_thread;
  const std::function<void()> second = [&f] { f(1, 2); };
  helper.start(&second);
  std::exception_ptr mine;
  try {
    f(0, 2);
  } catch (...) {
    mine = std::current_exception();
  }
  const std::exception_ptr theirs = helper.wait();
  helper.release();
  if (mine) std::rethrow_exception(mine);
  if (theirs) std::rethrow_exception(theirs);
}

}  // namespace vproto::sim
