#pragma once
// Output files appear whole or not at all (cli.md): written to a temporary name in the
// same directory, then renamed.

#include <filesystem>
#include <functional>
#include <string>

namespace vproto::ui_batch {

/// Calls `write(tmp_path)` and renames the result to `path`; removes the temporary file
/// and throws InputError naming `path` when writing fails.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path&)>& write);

/// Writes a text file atomically.
void write_text_atomically(const std::filesystem::path& path, const std::string& text);

/// A run's hold on its output folder: created when missing, locked against a second run
/// (DIR/.vproto.lock, released when this ends, even if the process is killed), and
/// cleared of what an earlier, concurrent-then-finished or killed run left there (its
/// summary.json, history.csv, build.json, animation.mp4, frames/, meshes/, plots/ and
/// half-written temporary files; the compile cache and anything else stay). Throws
/// InputError naming the folder when it cannot be written or another run holds it.
class OutputFolder {
 public:
  explicit OutputFolder(const std::filesystem::path& dir);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

 private:
  int lock_fd_ = -1;
};

}  // namespace vproto::ui_batch
