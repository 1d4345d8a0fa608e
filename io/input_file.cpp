#include "io/input_file.h"

#include <fcntl.h>
#include <locale.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "io/input_error.h"

namespace subd2nurbs {

namespace {

/// Closes a descriptor on every path out.
struct Descriptor {
  int fd;
  ~Descriptor() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

std::string lowercase_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

const char* file_kind(unsigned mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string printable(std::string_view text, std::size_t max_bytes) {
  auto escape = [](std::string_view s) {
    std::string out;
    out.reserve(s.size());
    for (const unsigned char c : s) {
      if (c >= 0x20 && c < 0x7f) {
        out += static_cast<char>(c);
      } else {
        char buffer[8];
        std::snprintf(buffer, sizeof buffer, "\\x%02x", c);
        out += buffer;
      }
    }
    return out;
  };
  if (text.size() <= max_bytes) return escape(text);
  const std::size_t head = max_bytes * 2 / 3, tail = max_bytes - head;
  return escape(text.substr(0, head)) + "...(" + std::to_string(text.size()) + " bytes)..." +
         escape(text.substr(text.size() - tail));
}

std::string read_input_file(const std::string& path, const std::string& what) {
  if (path.empty()) throw InputError("(empty name)", 0, "no input file name given");
  // lstat-free on purpose: a symbolic link to a regular file is a regular input.
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT || err == ENOTDIR) throw InputError(path, 0, "no such file");
    throw InputError(path, 0, std::string("cannot open the file: ") + std::strerror(err));
  }
  if (!S_ISREG(st.st_mode))
    throw InputError(path, 0, std::string("is ") + file_kind(st.st_mode) + ", not " + what +
                                  " (only regular files are read)");
  // O_NONBLOCK: should the file have been swapped for a FIFO since the stat, opening it
  // does not wait for a writer; fstat below then refuses it.
  Descriptor d{::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY)};
  if (d.fd < 0) {
    const int err = errno;
    throw InputError(path, 0, std::string("cannot open the file: ") + std::strerror(err));
  }
  if (::fstat(d.fd, &st) != 0 || !S_ISREG(st.st_mode))
    throw InputError(path, 0, std::string("is ") + file_kind(st.st_mode) + ", not " + what +
                                  " (only regular files are read)");
  if (static_cast<unsigned long long>(st.st_size) > kMaxInputFileBytes)
    throw InputError(path, 0, "the file has " + std::to_string(st.st_size) + " bytes; at most " +
                                  std::to_string(kMaxInputFileBytes) + " are read");
  std::string contents(static_cast<std::size_t>(st.st_size), '\0');
  std::size_t have = 0;
  for (;;) {
    if (have == contents.size()) {
      // The file grew since fstat: keep reading, within the cap.
      if (contents.size() >= kMaxInputFileBytes)
        throw InputError(path, 0, "the file grows beyond " + std::to_string(kMaxInputFileBytes) +
                                      " bytes while being read");
      contents.resize(contents.size() + 65536);
    }
    const ssize_t got = ::read(d.fd, &contents[have], contents.size() - have);
    if (got < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      throw InputError(path, 0, std::string("reading the file failed: ") + std::strerror(err));
    }
    if (got == 0) break;
    have += static_cast<std::size_t>(got);
  }
  contents.resize(have);
  return contents;
}

bool parse_double(std::string_view token, double& value) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (ptr != end) return false;
  if (ec == std::errc::result_out_of_range) {
    // from_chars leaves `value` unset here; strtod saturates (input_file.h), read in the C
    // locale since the token's decimal point is '.'.
    static const locale_t c_locale = ::newlocale(LC_NUMERIC_MASK, "C", locale_t{});
    value = ::strtod_l(std::string(token).c_str(), nullptr, c_locale);
    return true;
  }
  return ec == std::errc();
}

}  // namespace subd2nurbs
