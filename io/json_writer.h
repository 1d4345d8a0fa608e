// The one JSON writer of the project: the patch JSON (io/patch_json.h), the conversion report
// and its quality section, and `check --json` (converter/pipeline/report.h), `info --json` and
// the fair report (converter/cli) are all written with it, by the CLI and the Python module alike.
//
// It writes text as it goes, with the layout the caller asks for: items inline ("a": 1, "b": 2),
// or a container's items one a line at an indent, or a line break before one item. So a
// document keeps its layout byte for byte while its members are written by name.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "core/util/point3.h"

namespace subd2nurbs {

class JsonWriter {
 public:
  /// What a number JSON has no form for becomes.
  enum class Numbers {
    /// Reports: a measure that is not finite (undefined) is null; -0 is "-0".
    Report,
    /// Geometry (the patch JSON): a value that is not finite throws std::invalid_argument
    /// "<document>: non-finite value in <what>"; -0 is "-0.0" (many readers take "-0" as the
    /// integer 0).
    Exact,
  };
  /// Separators: "," and ":" (Compact) or ", " and ": " (Spaced).
  enum class Spacing { Compact, Spaced };

  /// `document` names the text in the errors of Numbers::Exact ("patch JSON").
  JsonWriter(Numbers numbers, Spacing spacing, std::string document = "JSON");

  /// Containers. `items_indent` >= 0: each item on a line of its own, indented so many spaces,
  /// and the closing bracket on a line indented `close_indent` (an empty one stays {} / []);
  /// < 0: items inline.
  JsonWriter& begin_object(int items_indent = -1, int close_indent = 0) { return open('{', items_indent, close_indent); }
  JsonWriter& end_object() { return close('}'); }
  JsonWriter& begin_array(int items_indent = -1, int close_indent = 0) { return open('[', items_indent, close_indent); }
  JsonWriter& end_array() { return close(']'); }
  /// The next item of the open container starts a line indented `indent` spaces.
  JsonWriter& break_line(int indent);

  JsonWriter& key(std::string_view name);
  JsonWriter& number(double x, const char* what = "a number");
  JsonWriter& integer(long long i);
  JsonWriter& boolean(bool b);
  JsonWriter& string(std::string_view s);
  JsonWriter& null();
  /// [x, y, z] (numbers as number()).
  JsonWriter& point(const Point3& p, const char* what = "a point");
  /// An array of the integers of a container (std::vector, std::array).
  template <class Container>
  JsonWriter& integers(const Container& values) {
    begin_array();
    for (const auto& v : values) integer(static_cast<long long>(v));
    return end_array();
  }
  /// An array of the numbers of a container (as number()); braces make a std::vector.
  JsonWriter& numbers(const std::vector<double>& values, const char* what = "a number") {
    return numbers<std::vector<double>>(values, what);
  }
  template <class Container>
  JsonWriter& numbers(const Container& values, const char* what = "a number") {
    begin_array();
    for (const double x : values) number(x, what);
    return end_array();
  }
  /// A key and its value in one call: key(name).number(x) and so on.
  JsonWriter& member(std::string_view name, double x) { return key(name).number(x); }
  JsonWriter& member(std::string_view name, int i) { return key(name).integer(i); }
  JsonWriter& member(std::string_view name, long long i) { return key(name).integer(i); }
  JsonWriter& member(std::string_view name, bool b) { return key(name).boolean(b); }
  JsonWriter& member(std::string_view name, const char* s) { return key(name).string(s); }
  JsonWriter& member(std::string_view name, const std::string& s) { return key(name).string(s); }
  /// Several members in one call: members("a", 1, "b", 2.5, "c", "text").
  template <class Value, class... Rest>
  JsonWriter& members(std::string_view name, const Value& value, const Rest&... rest) {
    member(name, value);
    if constexpr (sizeof...(rest) > 0) members(rest...);
    return *this;
  }

  /// The text so far (append a final newline yourself).
  const std::string& text() const { return s_; }
  std::string take() { return std::move(s_); }

  /// A quoted, escaped JSON string.
  static std::string quoted(std::string_view s);
  /// A number as Numbers::Report writes it ("%.17g", exact as an IEEE double; null when not finite).
  static std::string report_number(double x);

 private:
  struct Level {
    int items_indent, close_indent;
    bool empty = true;
  };
  void before_item();
  JsonWriter& open(char bracket, int items_indent, int close_indent);
  JsonWriter& close(char bracket);

  Numbers numbers_;
  Spacing spacing_;
  std::string document_;
  std::string s_;
  std::vector<Level> stack_;
  bool after_key_ = false;
  int break_ = -1;
};

}  // namespace subd2nurbs
