#include "two_threads.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

#include "blas_threads.h"
#include "vproto/sim/elastic_contact.h"
#include "vproto/sim/linear_solver.h"

namespace vproto::sim {

namespace {

// The helper waits for work spinning a while before it sleeps, and the caller spins for the
// helper's end: a thread asleep on a futex takes 50-70 us to wake on this kind of machine,
// and the snap-fit makes about 12,000 two-thread calls, mostly 20-200 us apart (a Newton
// iteration's assembly, its LU's panels, W's products), each of which cost 80-100 us more
// than its work when both sides slept.
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
    failed_ = nullptr;
    done_.store(false, std::memory_order_relaxed);
    {
      const std::lock_guard<std::mutex> lock(mutex_);  // against a helper going to sleep
      task_.store(task, std::memory_order_release);
    }
    wake_.notify_one();
  }
  /// Takes the task back when the helper has not started it (it may not have had a core
  /// since: the renderer's thread or ffmpeg's held it); whether it did.
  bool take_back() { return task_.exchange(nullptr, std::memory_order_acq_rel) != nullptr; }
  /// Waits for the task; its exception, if any.
  std::exception_ptr wait() {
    if (!spin_until([this] { return done_.load(std::memory_order_acquire); }, kCallerSpin, false)) {
      std::unique_lock<std::mutex> lock(mutex_);
      finished_.wait(lock, [this] { return done_.load(std::memory_order_acquire); });
    }
    return failed_;
  }

 private:
  static constexpr std::chrono::microseconds kHelperSpin{200}, kCallerSpin{2000};

  // polls `ready` for up to `limit`; whether it became true. A `polite` poller (the helper
  // waiting for work) gives the core to any other thread that wants it (the renderer's,
  // ffmpeg's) between polls after the first 20 us; the caller, on the run's critical path,
  // keeps its core.
  template <class Ready>
  static bool spin_until(Ready ready, std::chrono::microseconds limit, bool polite) {
    const auto start = std::chrono::steady_clock::now();
    const auto courteous = start + std::chrono::microseconds(20), until = start + limit;
    bool yielding = false;
    for (int k = 1;; ++k) {
      if (ready()) return true;
      if (yielding) {
        std::this_thread::yield();
      } else {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
      }
      if (yielding || k % 64 == 0) {
        const auto now = std::chrono::steady_clock::now();
        if (now > until) return ready();
        yielding = polite && now > courteous;
      }
    }
  }

  void loop() {
    for (;;) {
      const std::function<void()>* task = nullptr;
      auto take = [&] {
        task = task_.exchange(nullptr, std::memory_order_acquire);
        return task != nullptr;
      };
      if (!spin_until(take, kHelperSpin, true)) {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return stop_ || take(); });
        if (!task) return;  // stopping
      }
      std::exception_ptr failed;
      try {
        (*task)();
      } catch (...) {
        failed = std::current_exception();
      }
      failed_ = failed;
      {
        const std::lock_guard<std::mutex> lock(mutex_);  // against a caller going to sleep
        done_.store(true, std::memory_order_release);
      }
      finished_.notify_all();
    }
  }

  std::mutex claim_;
  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  std::atomic<const std::function<void()>*> task_{nullptr};
  std::exception_ptr failed_;  // written before done_ is set, read after it is seen
  std::atomic<bool> done_{true};
  bool stop_ = false;
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
  // the helper's part on this thread when the helper has not begun it: waiting for a thread
  // that has no core would leave this one idle (each part's answer is the same on either)
  std::exception_ptr theirs;
  if (helper.take_back()) {
    try {
      second();
    } catch (...) {
      theirs = std::current_exception();
    }
  } else {
    theirs = helper.wait();
  }
  helper.release();
  if (mine) std::rethrow_exception(mine);
  if (theirs) std::rethrow_exception(theirs);
}

}  // namespace vproto::sim
