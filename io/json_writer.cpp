#include "io/json_writer.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

namespace subd2nurbs {

namespace {

/// "%.17g", with a decimal comma (a non-C LC_NUMERIC locale) turned into a point.
std::string g17(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  for (char* c = buf; *c; ++c)
    if (*c == ',') *c = '.';
  return buf;
}

}  // namespace

JsonWriter::JsonWriter(Numbers numbers, Spacing spacing, std::string document)
    : numbers_(numbers), spacing_(spacing), document_(std::move(document)) {}

std::string JsonWriter::quoted(std::string_view s) {
  std::string r = "\"";
  for (const unsigned char c : s) {
    switch (c) {
      case '"': r += "\\\""; break;
      case '\\': r += "\\\\"; break;
      case '\n': r += "\\n"; break;
      case '\r': r += "\\r"; break;
      case '\t': r += "\\t"; break;
      default:
        if (c < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
          r += buffer;
        } else {
          r += static_cast<char>(c);
        }
    }
  }
  return r + "\"";
}

std::string JsonWriter::report_number(double x) { return std::isfinite(x) ? g17(x) : std::string("null"); }

void JsonWriter::before_item() {
  if (after_key_) {  // a member's value follows its key
    after_key_ = false;
    return;
  }
  if (stack_.empty()) return;
  Level& level = stack_.back();
  const bool first = level.empty;
  level.empty = false;
  if (!first) s_ += ',';
  const int indent = break_ >= 0 ? break_ : level.items_indent;
  break_ = -1;
  if (indent >= 0) {
    s_ += '\n';
    s_.append(static_cast<size_t>(indent), ' ');
  } else if (!first && spacing_ == Spacing::Spaced) {
    s_ += ' ';
  }
}

JsonWriter& JsonWriter::open(char bracket, int items_indent, int close_indent) {
  before_item();
  s_ += bracket;
  stack_.push_back({items_indent, close_indent});
  return *this;
}

JsonWriter& JsonWriter::close(char bracket) {
  if (stack_.empty()) throw std::logic_error("JsonWriter: closing a container that is not open");
  const Level level = stack_.back();
  stack_.pop_back();
  break_ = -1;
  if (level.items_indent >= 0 && !level.empty) {
    s_ += '\n';
    s_.append(static_cast<size_t>(level.close_indent), ' ');
  }
  s_ += bracket;
  return *this;
}

JsonWriter& JsonWriter::break_line(int indent) {
  break_ = indent;
  return *this;
}

JsonWriter& JsonWriter::key(std::string_view name) {
  before_item();
  s_ += quoted(name);
  s_ += spacing_ == Spacing::Spaced ? ": " : ":";
  after_key_ = true;
  return *this;
}

JsonWriter& JsonWriter::number(double x, const char* what) {
  before_item();
  if (numbers_ == Numbers::Report) {
    s_ += report_number(x);
  } else if (!std::isfinite(x)) {
    throw std::invalid_argument(document_ + ": non-finite value in " + what);
  } else if (x == 0 && std::signbit(x)) {
    s_ += "-0.0";
  } else {
    s_ += g17(x);
  }
  return *this;
}

JsonWriter& JsonWriter::integer(long long i) {
  before_item();
  s_ += std::to_string(i);
  return *this;
}

JsonWriter& JsonWriter::boolean(bool b) {
  before_item();
  s_ += b ? "true" : "false";
  return *this;
}

JsonWriter& JsonWriter::string(std::string_view str) {
  before_item();
  s_ += quoted(str);
  return *this;
}

JsonWriter& JsonWriter::null() {
  before_item();
  s_ += "null";
  return *this;
}

JsonWriter& JsonWriter::point(const Point3& p, const char* what) {
  begin_array();
  for (const double x : p) number(x, what);
  return end_array();
}

}  // namespace subd2nurbs
