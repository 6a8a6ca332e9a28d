// Loops split over two threads, deterministically: items k = first, first + stride, ...
// are dealt to f(0, 2) on the calling thread and f(1, 2) on a helper thread (or taken in
// turn from a counter the two share), each item is done by exactly one of them, and its
// result does not depend on which (or on how many threads there are). For the compliance
// columns, the Delassus blocks and the Newton systems of the elastic contact stage, where
// the snap-fit's second core otherwise idles. The helper spins a while for its next task
// and the caller for the helper's end (two_threads.cpp): calls come 20-200 us apart.
#pragma once

#include <functional>

namespace vproto::sim {

/// Runs f(1, 2) on the process's one helper thread (started on first use, kept for the
/// process: a thread a call would cost OpenBLAS a buffer each time) and f(0, 2) here, and
/// waits for both; or f(0, 1) alone when not `wanted`, on a one-core machine, under mpirun
/// with more than one rank, or while the helper works for another caller. The items must write
/// apart from each other. An exception from either is rethrown here after both have ended. OpenBLAS
/// stays on one thread throughout (each thread's own guard would otherwise hand the other back its
/// thread pool, whose idle workers then spin on the core the other needs).
void in_two_threads(bool wanted, const std::function<void(int first, int stride)>& f);

}  // namespace vproto::sim
