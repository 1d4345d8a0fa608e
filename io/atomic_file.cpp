#include "io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>

#include "io/input_error.h"

namespace subd2nurbs {

namespace {

std::string system_error_text(int err) { return std::strerror(err); }

std::string directory_of(const std::string& path) {
  const std::string::size_type slash = path.rfind('/');
  if (slash == std::string::npos) return "";
  return path.substr(0, slash + 1);  // keeps the slash; "/" for files in the root
}

std::string file_name_of(const std::string& path) {
  const std::string::size_type slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

/// Creates a new, empty, uniquely named file next to `path` (".NAME.XXXXXXXX.tmp") and
/// returns its name. The file is created with O_EXCL, so an existing file is never reused.
std::string create_temporary_next_to(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  std::random_device entropy;
  const std::string prefix = directory_of(path) + "." + file_name_of(path) + ".";
  int err = 0;
  for (int attempt = 0; attempt < 16; ++attempt) {
    char suffix[32];
    std::snprintf(suffix, sizeof suffix, "%08x", entropy() ^ (counter++ * 2654435761u));
    const std::string name = prefix + suffix + ".tmp";
    // 0666 filtered by the umask: the same permissions a plain std::ofstream would give.
    const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      ::close(fd);
      return name;
    }
    err = errno;
    if (err != EEXIST) break;
  }
  const std::string dir = directory_of(path).empty() ? "." : directory_of(path);
  throw WriteError(path, "cannot create a temporary file in directory '" + dir +
                             "': " + system_error_text(err));
}

/// Forces the file's data to disk, so that the rename cannot expose an empty file after a
/// crash. Returns 0 or an errno value.
int sync_to_disk(const std::string& name) {
  const int fd = ::open(name.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return errno;
  const int result = ::fsync(fd) == 0 ? 0 : errno;
  ::close(fd);
  return result;
}

}  // namespace

void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& writer) {
  if (path.empty()) throw WriteError("(empty path)", "no output file name given");
  const std::string temporary = create_temporary_next_to(path);
  auto fail = [&](const std::string& message) {
    std::remove(temporary.c_str());
    throw WriteError(path, message);
  };

  // Replacing an existing file keeps its permissions.
  struct stat existing;
  if (::stat(path.c_str(), &existing) == 0 && S_ISREG(existing.st_mode))
    ::chmod(temporary.c_str(), existing.st_mode & 07777);

  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) fail("cannot open temporary file '" + temporary + "' for writing");
    try {
      writer(out);
    } catch (...) {
      out.close();
      std::remove(temporary.c_str());
      throw;
    }
    out.flush();
    if (!out) fail("writing failed (disk full or I/O error?)");
    out.close();
    if (!out) fail("closing the file failed (disk full or I/O error?)");
  }
  if (const int err = sync_to_disk(temporary)) fail("cannot flush to disk: " + system_error_text(err));
  if (std::rename(temporary.c_str(), path.c_str()) != 0)
    fail("cannot replace the file: " + system_error_text(errno));
}

}  // namespace subd2nurbs
