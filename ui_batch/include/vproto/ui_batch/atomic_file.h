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

}  // namespace vproto::ui_batch
