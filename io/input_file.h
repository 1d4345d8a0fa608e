// Reading an input file safely: regular files only (a FIFO, directory, socket or device is
// refused before anything could block on it), a size cap, names made printable for messages,
// and numbers parsed the same in every locale.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace subd2nurbs {

/// Input files larger than this are refused (an OBJ cage of this size has ~40M faces).
constexpr std::size_t kMaxInputFileBytes = std::size_t{2} << 30;  // 2 GiB

/// The whole content of `path`.
/// \throw InputError naming the file when it does not exist, cannot be opened, is not a
/// regular file (FIFO, directory, device, socket: refused without reading, so nothing
/// blocks), is larger than kMaxInputFileBytes, or reading fails. `what` names the expected
/// content in messages ("an OBJ file", "a glTF file", ...).
std::string read_input_file(const std::string& path, const std::string& what);

/// The file name's extension in lower case, with its dot (".stl"), or "" if it has none.
std::string lowercase_extension(const std::string& path);

/// "a directory", "a FIFO (named pipe)", "a character device", ... for a stat() st_mode.
const char* file_kind(unsigned mode);

/// `text` made safe to echo in a message: control bytes, NUL and bytes >= 0x7f shown as
/// \xNN (so a file name or token never moves the terminal or hides text), and anything longer
/// than `max_bytes` shortened to its start and end around "...".
std::string printable(std::string_view text, std::size_t max_bytes = 160);

/// Parses the whole token as a double (locale independent, correctly rounded; accepts
/// "nan", "inf" and a leading '+'). Values beyond the double range become +-inf (the caller's
/// range check then rejects them), values below it 0 or a subnormal, as with strtod.
bool parse_double(std::string_view token, double& value);

}  // namespace subd2nurbs
