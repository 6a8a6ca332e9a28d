#include <csignal>
#include <iostream>

#include "vproto/ui_batch/cli.h"

int main(int argc, char** argv) {
  // a helper process that dies (ffmpeg) must not take vproto down with SIGPIPE
  std::signal(SIGPIPE, SIG_IGN);
  return vproto::ui_batch::run_cli(std::vector<std::string>(argv + 1, argv + argc), std::cerr);
}
