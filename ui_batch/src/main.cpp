#include <iostream>

#include "vproto/ui_batch/cli.h"

int main(int argc, char** argv) {
  return vproto::ui_batch::run_cli(std::vector<std::string>(argv + 1, argv + argc), std::cerr);
}
