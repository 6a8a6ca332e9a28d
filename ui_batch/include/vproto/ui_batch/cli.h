#pragma once
// The `vproto` command line (cli.md): check, build, run, bench.

#include <iosfwd>
#include <string>
#include <vector>

namespace vproto::ui_batch {

/// Runs one command; returns the process exit code (0 ok, 1 internal error, 2 bad input,
/// 3 simulation failed). Messages go to `err`.
int run_cli(const std::vector<std::string>& args, std::ostream& err);

}  // namespace vproto::ui_batch
