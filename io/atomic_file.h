// Writing files so that readers never see them half-written, and a run that fails (or is
// interrupted by SIGINT / SIGTERM) leaves neither a partial file nor a temporary one.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace subd2nurbs {

/// The file an output name refers to, checked before any work is done:
/// * a symbolic link is followed: the file it points to is replaced and the link is kept
///   (a dangling link is refused: its target's directory may not exist);
/// * an existing output must be a regular file: a directory, FIFO, device or socket is
///   refused (nothing is opened, so nothing blocks; a device node is never replaced);
/// * the directory must exist and be writable.
/// Returns the path to write (the link's target, or `path`).
/// \throw WriteError naming `path`
std::string resolve_output_path(const std::string& path);

/// True when both names exist and are the same file (same device and inode; links followed).
bool same_file(const std::string& a, const std::string& b);

/// A new temporary file next to an output (".NAME.XXXXXXXX.tmp" in the directory of the
/// resolved output, created with O_EXCL), filled by the caller, then renamed over the output
/// by commit(). Destroyed without commit(), it removes the temporary file. While it exists,
/// its name is registered with the SIGINT / SIGTERM handler (install_signal_cleanup).
/// Several staged files committed one after the other give "all outputs or none" up to the
/// renames themselves.
class StagedFile {
 public:
  /// \throw WriteError naming `path` (see resolve_output_path)
  explicit StagedFile(const std::string& path);
  ~StagedFile();
  StagedFile(StagedFile&& other) noexcept;
  StagedFile& operator=(StagedFile&&) = delete;
  StagedFile(const StagedFile&) = delete;
  StagedFile& operator=(const StagedFile&) = delete;

  /// The temporary file's name (for writers that only take names, e.g. OCCT's).
  const std::string& name() const { return temporary_; }
  /// The output as given.
  const std::string& path() const { return path_; }

  /// Fills the temporary file through a stream. An exception from `writer` is passed on.
  /// \throw WriteError when the file cannot be written
  void write(const std::function<void(std::ostream&)>& writer);

  /// Forces the file to disk and renames it over the output. \throw WriteError
  void commit();

 private:
  std::string path_;       ///< as given
  std::string target_;     ///< resolved (a symbolic link's target)
  std::string temporary_;  ///< empty once committed or moved from
  int slot_ = -1;          ///< in the signal cleanup registry
};

/// Calls `writer` with a stream onto a new temporary file in the directory of `path`, then
/// flushes it to disk and renames it over `path` (StagedFile: write, commit). Either `path`
/// ends up holding the complete new content, or it is left as it was (an existing file is
/// never truncated) and no temporary file remains.
/// \throw WriteError naming `path` if the file cannot be created, written or renamed.
/// An exception thrown by `writer` itself is passed on unchanged (after the cleanup).
void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& writer);

/// Installs SIGINT / SIGTERM / SIGHUP handlers that remove the temporary files of live
/// StagedFiles and then end the process as the signal would have. For programs (the CLI);
/// a library embedding subd2nurbs (Python) keeps its own handlers.
void install_signal_cleanup();

}  // namespace subd2nurbs
