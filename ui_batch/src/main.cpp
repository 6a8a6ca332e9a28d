#include <chrono>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <thread>

#include "vproto/materials/errors.h"
#include "vproto/sim/linear_solver.h"
#include "vproto/ui_batch/cli.h"

int main(int argc, char** argv) {
  // a helper process that dies (ffmpeg) must not take vproto down with SIGPIPE
  std::signal(SIGPIPE, SIG_IGN);
  // Mesa's software rasterizer draws the frames on the renderer's own thread, not on one more
  // thread per core: the renderer works beside a simulation that keeps both cores busy, and
  // its extra threads only took cores from it (the snap-fit: 0.2 s less end to end, the same
  // pixels). Set before any thread starts; a value the user set stays.
  ::setenv("LP_NUM_THREADS", "0", 0);
  const std::vector<std::string> args(argv + 1, argv + argc);
  // under mpirun with several ranks, MPI and PETSc start before anything else
  try {
    vproto::sim::start_parallel();
  } catch (const vproto::InputError& e) {
    if (vproto::sim::launched_rank() == 0) std::cerr << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    if (vproto::sim::launched_rank() == 0)
      std::cerr << "vproto: MPI would not start: " << e.what() << "\n";
    return 1;
  }
  if (vproto::sim::launched_rank() == 0) {
    const int code = vproto::ui_batch::run_cli(args, std::cerr);
    // a failure of this rank alone would leave the others waiting in a solve
    if (code != 0 && vproto::sim::launched_ranks() > 1 && !vproto::sim::ranks_finished_together()) {
      std::cerr.flush();
      vproto::sim::abort_parallel(code);
    }
    vproto::sim::finish_parallel();
    return code;
  }
  // another rank says nothing unless it fails alone: a failure every rank meets is rank
  // 0's to report (it ends the job), so this one waits before it speaks and ends the job
  std::ostringstream quiet;
  const int code = vproto::ui_batch::run_cli(args, quiet);
  if (code != 0) {
    std::this_thread::sleep_for(std::chrono::seconds(3));
    std::cerr << "vproto (MPI rank " << vproto::sim::launched_rank() << "): " << quiet.str();
    std::cerr.flush();
    vproto::sim::abort_parallel(code);
  }
  vproto::sim::finish_parallel();
  return code;
}
