#include "vproto/ui_batch/atomic_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <fstream>

#include "vproto/materials/errors.h"

namespace vproto::ui_batch {

namespace fs = std::filesystem;

void write_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  const fs::path tmp =
      path.parent_path() / ("." + path.filename().string() + ".tmp" + std::to_string(::getpid()));
  try {
    write(tmp);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError("cannot write '" + path.string() + "': " + ec.message());
  }
}

void write_text_atomically(const fs::path& path, const std::string& text) {
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out)
      throw InputError("cannot write '" + path.string() +
                       "': check the folder exists and is writable");
  });
}

OutputFolder::OutputFolder(const fs::path& dir) {
  const SourceLoc where{dir.string(), 0, 0};
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir) || ::access(dir.c_str(), W_OK) != 0)
    throw InputError(
        where, "cannot write to the output folder" + (ec ? ": " + ec.message() : std::string()));
  const fs::path lock = dir / ".vproto.lock";
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) throw InputError(where, "cannot create the lock file '" + lock.string() + "'");
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw InputError(where, "another vproto run is writing to this folder (it holds " +
                                lock.string() + "); wait for it to end, or give another -o");
  }
  // what an earlier run wrote goes, so nothing old stands beside the new outputs
  for (const char* name :
       {"summary.json", "history.csv", "contact_steps.csv", "build.json", "animation.mp4"})
    fs::remove(dir / name, ec);
  for (const char* name : {"frames", "meshes", "plots"}) fs::remove_all(dir / name, ec);
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > 1 && name[0] == '.' && name.find(".tmp") != std::string::npos &&
        entry.is_regular_file())
      fs::remove(entry.path(), ec);  // half-written by a killed run
  }
}

OutputFolder::~OutputFolder() {
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the lock
}

}  // namespace vproto::ui_batch
