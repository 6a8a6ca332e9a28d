// OpenBLAS on one thread for the duration of a scope. The triangular solves with the kept
// factor and the contact solver's LU work on blocks too small for a second thread to pay
// for itself, and OpenBLAS's idle workers spin (sched_yield) for a while after each call:
// on the snap-fit, 27 s of system time on the second core, which the renderer needs, and
// the run 25 % slower. Factorizations keep OpenBLAS's threads. Looked up weakly: another
// BLAS has no such control and the guard then does nothing.
#pragma once

extern "C" {
int openblas_get_num_threads() __attribute__((weak));
void openblas_set_num_threads(int) __attribute__((weak));
}

namespace vproto::sim {

class OneBlasThread {
 public:
  OneBlasThread() {
    if (openblas_get_num_threads == nullptr || openblas_set_num_threads == nullptr) return;
    threads_ = openblas_get_num_threads();
    if (threads_ > 1) openblas_set_num_threads(1);
  }
  ~OneBlasThread() {
    if (threads_ > 1) openblas_set_num_threads(threads_);
  }
  OneBlasThread(const OneBlasThread&) = delete;
  OneBlasThread& operator=(const OneBlasThread&) = delete;

 private:
  int threads_ = 0;
};

}  // namespace vproto::sim
