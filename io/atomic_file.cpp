#include "io/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>

#include "io/input_error.h"
#include "io/input_file.h"

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

// --- temporary files removed on SIGINT / SIGTERM / SIGHUP ------------------------------------
// A fixed table of heap-allocated names: registering and the handler only use atomics,
// and the handler only calls unlink(), which is async-signal-safe.

constexpr int kSlots = 64;
std::array<std::atomic<char*>, kSlots> g_temporaries{};

int register_temporary(const std::string& name) {
  char* copy = ::strdup(name.c_str());
  if (!copy) return -1;
  for (int i = 0; i < kSlots; ++i) {
    char* expected = nullptr;
    if (g_temporaries[i].compare_exchange_strong(expected, copy)) return i;
  }
  std::free(copy);  // more than kSlots outputs at once: this one is not cleaned on a signal
  return -1;
}

void unregister_temporary(int slot) {
  if (slot < 0) return;
  std::free(g_temporaries[slot].exchange(nullptr));
}

extern "C" void remove_temporaries_and_die(int signal_number) {
  for (auto& slot : g_temporaries)
    if (char* name = slot.load()) ::unlink(name);
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

/// Creates a new, empty, uniquely named file next to `target` (".NAME.XXXXXXXX.tmp", NAME
/// shortened so that the temporary name stays a valid file name) and returns its name.
/// O_EXCL: an existing file is never reused. The name is registered for removal on a signal
/// (`slot`) before the file is created, so that no signal can leave it behind; a name that
/// turns out to exist already is unregistered before the next is tried.
std::string create_temporary_next_to(const std::string& path, const std::string& target, int& slot) {
  static std::atomic<unsigned> counter{0};
  std::random_device entropy;
  std::string name = file_name_of(target);
  if (name.size() > 100) name.resize(100);
  const std::string prefix = directory_of(target) + "." + name + ".";
  int err = 0;
  for (int attempt = 0; attempt < 16; ++attempt) {
    char suffix[32];
    std::snprintf(suffix, sizeof suffix, "%08x", entropy() ^ (counter++ * 2654435761u));
    const std::string candidate = prefix + suffix + ".tmp";
    slot = register_temporary(candidate);
    // 0666 filtered by the umask: the same permissions a plain std::ofstream would give.
    const int fd = ::open(candidate.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      ::close(fd);
      return candidate;
    }
    err = errno;
    unregister_temporary(slot);
    slot = -1;
    if (err != EEXIST) break;
  }
  const std::string dir = directory_of(target).empty() ? "." : directory_of(target);
  throw WriteError(path, "cannot create a temporary file in directory '" + printable(dir) +
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

std::string resolve_output_path(const std::string& path) {
  if (path.empty()) throw WriteError("(empty path)", "no output file name given");
  std::string target = path;
  struct stat st;
  if (::lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) {
    char* real = ::realpath(path.c_str(), nullptr);
    if (!real) {
      char link[PATH_MAX + 1];
      const ssize_t n = ::readlink(path.c_str(), link, PATH_MAX);
      const std::string to = n > 0 ? std::string(link, static_cast<size_t>(n)) : std::string("?");
      throw WriteError(path, "is a symbolic link to '" + printable(to) +
                                 "', which does not exist (a link's target is replaced, never the link)");
    }
    target = real;
    std::free(real);
  }
  if (::stat(target.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode))
      throw WriteError(path, std::string("is ") + file_kind(st.st_mode) +
                                 "; outputs must be regular files (nothing was written)");
  } else if (errno != ENOENT) {
    throw WriteError(path, system_error_text(errno));
  }
  const std::string dir = directory_of(target).empty() ? "." : directory_of(target);
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw WriteError(path, "the directory " + printable(dir) + " does not exist");
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw WriteError(path, "the directory " + printable(dir) + " is not writable");
  return target;
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

StagedFile::StagedFile(const std::string& path) : path_(path), target_(resolve_output_path(path)) {
  temporary_ = create_temporary_next_to(path_, target_, slot_);
  // Replacing an existing file keeps its permissions.
  struct stat existing;
  if (::stat(target_.c_str(), &existing) == 0 && S_ISREG(existing.st_mode))
    ::chmod(temporary_.c_str(), existing.st_mode & 07777);
}

StagedFile::StagedFile(StagedFile&& other) noexcept
    : path_(std::move(other.path_)), target_(std::move(other.target_)),
      temporary_(std::move(other.temporary_)), slot_(other.slot_) {
  other.temporary_.clear();
  other.slot_ = -1;
}

StagedFile::~StagedFile() {
  if (!temporary_.empty()) std::remove(temporary_.c_str());
  unregister_temporary(slot_);
}

void StagedFile::write(const std::function<void(std::ostream&)>& writer) {
  std::ofstream out(temporary_, std::ios::binary | std::ios::trunc);
  if (!out) throw WriteError(path_, "cannot open temporary file '" + printable(temporary_) + "' for writing");
  writer(out);
  out.flush();
  if (!out) throw WriteError(path_, "writing failed (disk full or I/O error?)");
  out.close();
  if (!out) throw WriteError(path_, "closing the file failed (disk full or I/O error?)");
}

void StagedFile::commit() {
  if (temporary_.empty()) throw WriteError(path_, "internal error: the file was already committed");
  if (const int err = sync_to_disk(temporary_)) throw WriteError(path_, "cannot flush to disk: " + system_error_text(err));
  if (std::rename(temporary_.c_str(), target_.c_str()) != 0)
    throw WriteError(path_, "cannot replace the file: " + system_error_text(errno));
  temporary_.clear();
  unregister_temporary(slot_);
  slot_ = -1;
}

void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& writer) {
  StagedFile file(path);
  file.write(writer);
  file.commit();
}

void install_signal_cleanup() {
  struct sigaction action {};
  action.sa_handler = remove_temporaries_and_die;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  for (int s : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(s, &action, nullptr);
}

}  // namespace subd2nurbs
