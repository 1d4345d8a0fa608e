// Reading PLY 1.0 (io/mesh_reader.h): ascii, binary_little_endian and binary_big_endian.
//
// The header (text lines up to `end_header`) declares elements, each with a count and
// properties: scalars of type char / uchar / short / ushort / int / uint / float / double (or
// int8 / uint8 / int16 / uint16 / int32 / uint32 / float32 / float64), and lists (`property
// list COUNT_TYPE ITEM_TYPE name`). Read: the scalar properties x, y, z of element `vertex`, and
// the list `vertex_indices` (or `vertex_index`) of element `face`; every other property and
// element is skipped, lists included. `comment` and `obj_info` lines are ignored. Without a
// face element (or with 0 faces) the file is a point cloud.
//
// Every count is checked against the bytes present before anything is allocated from it:
// in binary files against the smallest size its element takes, in ASCII files against the
// characters left (each value takes at least two).
#include <algorithm>
#include <cstring>
#include <optional>

#include "core/mesh/validate.h"
#include "io/input_file.h"
#include "io/mesh_reader_detail.h"

namespace subd2nurbs {

namespace {

using mesh_detail::quoted;
using mesh_detail::RawMesh;
using mesh_detail::TextCursor;

enum class Type { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool type_of(std::string_view name, Type& type) {
  static const std::pair<std::string_view, Type> kNames[] = {
      {"char", Type::Int8},     {"int8", Type::Int8},       {"uchar", Type::UInt8},   {"uint8", Type::UInt8},
      {"short", Type::Int16},   {"int16", Type::Int16},     {"ushort", Type::UInt16}, {"uint16", Type::UInt16},
      {"int", Type::Int32},     {"int32", Type::Int32},     {"uint", Type::UInt32},   {"uint32", Type::UInt32},
      {"float", Type::Float32}, {"float32", Type::Float32}, {"double", Type::Float64}, {"float64", Type::Float64}};
  for (const auto& [n, t] : kNames)
    if (n == name) {
      type = t;
      return true;
    }
  return false;
}

std::size_t size_of(Type t) {
  switch (t) {
    case Type::Int8: case Type::UInt8: return 1;
    case Type::Int16: case Type::UInt16: return 2;
    case Type::Int32: case Type::UInt32: case Type::Float32: return 4;
    case Type::Float64: return 8;
  }
  return 1;
}

bool is_float(Type t) { return t == Type::Float32 || t == Type::Float64; }

struct Property {
  std::string name;
  bool list = false;
  Type count_type = Type::UInt8;  ///< lists only
  Type type = Type::Float32;      ///< the scalar's, or the list items'
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  int line = 0;  ///< of its declaration
  std::vector<Property> properties;
};

enum class Format { Ascii, LittleEndian, BigEndian };

/// One value of the binary body as a double (every PLY scalar type fits exactly).
double binary_value(const unsigned char* p, Type t, bool big_endian) {
  unsigned char b[8];
  const std::size_t n = size_of(t);
  for (std::size_t i = 0; i < n; ++i) b[i] = big_endian ? p[n - 1 - i] : p[i];
  switch (t) {
    case Type::Int8: return static_cast<std::int8_t>(b[0]);
    case Type::UInt8: return b[0];
    case Type::Int16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
    case Type::UInt16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
    case Type::Int32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
    case Type::UInt32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
    case Type::Float32: { float v; std::memcpy(&v, b, 4); return v; }
    case Type::Float64: { double v; std::memcpy(&v, b, 8); return v; }
  }
  return 0;
}

/// Reads one file: the header, then each element's items in turn.
class PlyReader {
 public:
  PlyReader(std::string_view bytes, const std::string& name, const MeshReadOptions& options)
      : bytes_(bytes), name_(name), options_(options) {}

  RawMesh read() {
    header();
    if (format_ == Format::Ascii) {
      raw_.locator = LoadedCage::Locator::Line;
      text_.emplace(bytes_.substr(body_), body_line_);
    } else {
      raw_.locator = LoadedCage::Locator::Element;
      offset_ = body_;
    }
    for (const Element& e : elements_) element(e);
    return std::move(raw_);
  }

 private:
  [[noreturn]] void fail(int line, const std::string& message) const { throw InputError(name_, line, message); }

  // --- header -----------------------------------------------------------------------------

  void header() {
    std::vector<std::string_view> tokens;
    // Line by line: the header is text even in a binary file.
    std::size_t pos = 0;
    int line = 0;
    bool ended = false;
    while (!ended) {
      if (pos >= bytes_.size()) fail(line, "the header has no 'end_header' line");
      std::size_t end = bytes_.find('\n', pos);
      if (end == std::string_view::npos) end = bytes_.size();
      std::string_view text = bytes_.substr(pos, end - pos);
      if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
      pos = end + 1;
      ++line;
      TextCursor words(text, line);
      tokens.clear();
      for (std::string_view t; words.next(t);) tokens.push_back(t);
      if (line == 1) {
        if (tokens.size() != 1 || tokens[0] != "ply") fail(0, "not a PLY file: it does not start with the line 'ply'");
        continue;
      }
      if (tokens.empty() || tokens[0] == "comment" || tokens[0] == "obj_info") continue;
      const std::string_view keyword = tokens[0];
      if (keyword == "format") {
        if (tokens.size() != 3) fail(line, "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
        if (tokens[1] == "ascii") format_ = Format::Ascii;
        else if (tokens[1] == "binary_little_endian") format_ = Format::LittleEndian;
        else if (tokens[1] == "binary_big_endian") format_ = Format::BigEndian;
        else fail(line, "unknown PLY format " + quoted(tokens[1]));
        if (tokens[2] != "1.0" && tokens[2] != "1") fail(line, "PLY version " + quoted(tokens[2]) + " is not supported (1.0 is)");
        has_format_ = true;
      } else if (keyword == "element") {
        std::int64_t count = 0;
        if (tokens.size() != 3 || !mesh_detail::parse_integer(tokens[2], count) || count < 0)
          fail(line, "expected 'element NAME COUNT'");
        elements_.push_back({std::string(tokens[1]), static_cast<std::uint64_t>(count), line, {}});
      } else if (keyword == "property") {
        if (elements_.empty()) fail(line, "a property before any element");
        Property p;
        const bool list = tokens.size() >= 2 && tokens[1] == "list";
        if (list ? tokens.size() != 5 : tokens.size() != 3)
          fail(line, "expected 'property TYPE NAME' or 'property list COUNT_TYPE ITEM_TYPE NAME'");
        p.list = list;
        if (list && !type_of(tokens[2], p.count_type)) fail(line, "unknown type " + quoted(tokens[2]));
        if (list && is_float(p.count_type)) fail(line, "a list count must have an integer type, not " + quoted(tokens[2]));
        if (!type_of(tokens[list ? 3 : 1], p.type)) fail(line, "unknown type " + quoted(tokens[list ? 3 : 1]));
        p.name = std::string(tokens[list ? 4 : 2]);
        elements_.back().properties.push_back(p);
      } else if (keyword == "end_header") {
        ended = true;
      } else {
        fail(line, "unknown header line " + quoted(keyword));
      }
    }
    if (!has_format_) fail(line, "the header has no 'format' line");
    body_ = pos > bytes_.size() ? bytes_.size() : pos;
    body_line_ = line + 1;
    // Which element holds what, checked once.
    for (const Element& e : elements_) {
      if (e.name == "vertex") {
        if (vertex_) fail(e.line, "a second 'vertex' element");
        vertex_ = &e;
        for (const char* axis : {"x", "y", "z"}) {
          const auto it = std::find_if(e.properties.begin(), e.properties.end(),
                                       [&](const Property& p) { return p.name == axis; });
          if (it == e.properties.end()) fail(e.line, std::string("element 'vertex' has no property '") + axis + "'");
          if (it->list) fail(e.line, std::string("property '") + axis + "' of element 'vertex' is a list");
        }
      } else if (e.name == "face") {
        if (face_) fail(e.line, "a second 'face' element");
        face_ = &e;
        const auto it = std::find_if(e.properties.begin(), e.properties.end(), [](const Property& p) {
          return p.name == "vertex_indices" || p.name == "vertex_index";
        });
        if (it == e.properties.end() || !it->list)
          fail(e.line, "element 'face' has no list property 'vertex_indices' (or 'vertex_index')");
        if (is_float(it->type)) fail(e.line, "the face's vertex indices must have an integer type");
        indices_ = &*it;
      }
    }
    if (!vertex_) fail(0, "the header declares no 'vertex' element");
  }

  // --- body -------------------------------------------------------------------------------

  /// Refuses a count the bytes left cannot hold (each item takes at least `min_bytes`).
  void check_count(const Element& e, std::size_t min_bytes) const {
    const bool mesh_element = &e == vertex_ || &e == face_;
    if (mesh_element && e.count > static_cast<std::uint64_t>(options_.max_elements))
      fail(e.line, "element '" + e.name + "' has " + std::to_string(e.count) + " items; at most " +
                       std::to_string(options_.max_elements) + " are read");
    const std::size_t left = bytes_.size() - (text_ ? body_ + text_->position() : offset_);
    // Binary: exactly (an element of fixed size is then skipped in one step); ASCII: the last
    // value needs no separator.
    if (min_bytes > 0 && e.count > left / min_bytes + (text_ ? 1 : 0))
      fail(e.line, "element '" + e.name + "' announces " + std::to_string(e.count) + " items, but only " +
                       std::to_string(left) + " bytes follow (each item takes at least " + std::to_string(min_bytes) +
                       ")");
  }

  void element(const Element& e) {
    if (e.properties.empty() || e.count == 0) return;
    // Smallest size of one item: its scalars, and each list's count.
    std::size_t min_bytes = 0;
    bool fixed = true;
    for (const Property& p : e.properties) {
      if (text_) min_bytes += 2;  // a value and a separator
      else min_bytes += size_of(p.list ? p.count_type : p.type);
      if (p.list) fixed = false;
    }
    check_count(e, min_bytes);
    if (&e != vertex_ && &e != face_ && fixed && !text_) {  // skipped whole
      offset_ += static_cast<std::size_t>(e.count) * min_bytes;
      return;
    }
    if (&e == vertex_) {
      raw_.positions.reserve(e.count);
      raw_.vertex_loc.reserve(e.count);
    } else if (&e == face_) {
      raw_.face_sizes.reserve(e.count);
      raw_.face_loc.reserve(e.count);
    }
    for (std::uint64_t i = 0; i < e.count; ++i) item(e, i);
  }

  [[noreturn]] void truncated(const Element& e, std::uint64_t i) const {
    fail(text_ ? text_->line() : 0, "the file ends inside " + e.name + " " + std::to_string(i) + " (the header announces " +
                                        std::to_string(e.count) + ")");
  }

  /// The next value: an ASCII token or binary bytes. `integer`: must be an integer.
  double value(const Element& e, std::uint64_t i, Type t, bool integer) {
    if (text_) {
      std::string_view token;
      if (!text_->next(token)) truncated(e, i);
      std::int64_t n = 0;
      if (mesh_detail::parse_integer(token, n)) return static_cast<double>(n);
      double x = 0;
      if (integer || !parse_double(token, x))
        fail(text_->line(), e.name + " " + std::to_string(i) + ": " + quoted(token) + " is not " +
                                (integer ? "an integer" : "a number"));
      return x;
    }
    const std::size_t n = size_of(t);
    if (bytes_.size() - offset_ < n) truncated(e, i);
    const double x = binary_value(reinterpret_cast<const unsigned char*>(bytes_.data()) + offset_, t,
                                  format_ == Format::BigEndian);
    offset_ += n;
    return x;
  }

  void item(const Element& e, std::uint64_t i) {
    std::array<double, 3> p{};
    int loc = static_cast<int>(std::min<std::uint64_t>(i + 1, 0x7fffffff));
    bool first = true;
    for (const Property& prop : e.properties) {
      if (!prop.list) {
        const double x = value(e, i, prop.type, false);
        if (first && text_) loc = text_->line();
        first = false;
        if (&e == vertex_ && prop.name.size() == 1 && prop.name[0] >= 'x' && prop.name[0] <= 'z')
          p[static_cast<std::size_t>(prop.name[0] - 'x')] = x;
        continue;
      }
      const double count = value(e, i, prop.count_type, true);
      if (first && text_) loc = text_->line();
      first = false;
      const bool indices = &prop == indices_;
      if (count < 0) fail(text_ ? text_->line() : 0, e.name + " " + std::to_string(i) + ": list '" + prop.name +
                                                          "' has a negative length " + std::to_string(count));
      if (indices && count > kMaxFaceSize)
        throw mesh_detail::error_at(name_, raw_.locator, "face", loc,
                                    "face has " + std::to_string(static_cast<std::uint64_t>(count)) +
                                        " vertices; at most " + std::to_string(kMaxFaceSize) + " are supported",
                                    MeshErrorCode::FaceTooLarge);
      // A list's items must be there before they are read (or skipped).
      const std::size_t left = bytes_.size() - (text_ ? body_ + text_->position() : offset_);
      const std::size_t item_bytes = text_ ? 2 : size_of(prop.type);
      if (count > static_cast<double>(left / item_bytes + 1)) truncated(e, i);
      const auto n = static_cast<std::size_t>(count);
      if (!indices) {
        if (text_) {
          for (std::size_t k = 0; k < n; ++k) value(e, i, prop.type, false);
        } else {
          if (n * item_bytes > left) truncated(e, i);
          offset_ += n * item_bytes;
        }
        continue;
      }
      raw_.face_sizes.push_back(static_cast<int>(n));
      raw_.face_loc.push_back(loc);
      for (std::size_t k = 0; k < n; ++k)
        raw_.face_indices.push_back(static_cast<std::int64_t>(value(e, i, prop.type, true)));
    }
    if (&e == vertex_) {
      raw_.positions.push_back(p);
      raw_.vertex_loc.push_back(loc);
    }
  }

  std::string_view bytes_;
  const std::string& name_;
  const MeshReadOptions& options_;
  Format format_ = Format::Ascii;
  bool has_format_ = false;
  std::vector<Element> elements_;
  const Element* vertex_ = nullptr;
  const Element* face_ = nullptr;
  const Property* indices_ = nullptr;  ///< the face's index list (the first of the two names)
  std::size_t body_ = 0;   ///< where the body starts
  int body_line_ = 1;      ///< its line (ASCII)
  std::size_t offset_ = 0; ///< binary: the next byte to read
  std::optional<TextCursor> text_;  ///< ASCII: the body's tokens
  RawMesh raw_;
};

}  // namespace

LoadedCage parse_ply(const std::string& bytes, const std::string& name, const MeshReadOptions& options) {
  return mesh_detail::finish_mesh(PlyReader(bytes, name, options).read(), name, options);
}

LoadedCage read_ply(const std::string& path, const MeshReadOptions& options) {
  return parse_ply(read_input_file(path, "a PLY file"), path, options);
}

}  // namespace subd2nurbs
