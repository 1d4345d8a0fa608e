// Writing a file so that readers never see it half-written.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace subd2nurbs {

/// Calls `writer` with a stream onto a new temporary file in the directory of `path`, then
/// flushes it to disk and renames it over `path`. Either `path` ends up holding the complete
/// new content, or it is left as it was (an existing file is never truncated) and no
/// temporary file remains.
/// \throw WriteError naming `path` if the file cannot be created, written or renamed.
/// An exception thrown by `writer` itself is passed on unchanged (after the cleanup).
void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& writer);

}  // namespace subd2nurbs
