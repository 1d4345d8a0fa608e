// Internals shared by the STL, PLY and OFF readers (io/mesh_reader.h): the mesh as the file
// gives it, the repairs that turn it into a cage, and a text cursor. Not for other callers.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/input_error.h"
#include "io/mesh_reader.h"

namespace subd2nurbs::mesh_detail {

/// A mesh as read, before any repair. Indices are as the file has them (checked later), and
/// every vertex and face has its location: a source line, or a 1-based element number.
struct RawMesh {
  std::vector<std::array<double, 3>> positions;
  std::vector<int> vertex_loc;
  std::vector<int> face_sizes;
  std::vector<std::int64_t> face_indices;
  std::vector<int> face_loc;
  LoadedCage::Locator locator = LoadedCage::Locator::Line;
  std::string face_unit = "face", vertex_unit = "vertex";
  Diagnostics diagnostics;
};

/// Checks, welds, drops, orients and recovers quads (the steps of io/mesh_reader.h).
/// \throw InputError naming the face or vertex (its line, or its element number).
LoadedCage finish_mesh(RawMesh raw, const std::string& name, const MeshReadOptions& options);

/// "FILE:LINE: message" for Locator::Line, "FILE: facet N: message" (N 0-based, as the file
/// counts) for Locator::Element; `loc` 0 (unknown) gives "FILE: message".
InputError error_at(const std::string& name, LoadedCage::Locator locator, const std::string& unit, int loc,
                    const std::string& message, std::optional<MeshErrorCode> code = std::nullopt);

/// A token of the file for a message: quoted, printable and shortened.
std::string quoted(std::string_view token);

/// Whitespace-separated tokens of a text, with line numbers ("\n", "\r\n" or a lone "\r"
/// end a line). `comment`, if not 0, starts a comment running to the end of its line.
class TextCursor {
 public:
  TextCursor(std::string_view text, int first_line = 1, char comment = 0)
      : text_(text), line_(first_line), comment_(comment) {}
  /// The next token, or false at the end of the text. `line()` is then the token's line.
  bool next(std::string_view& token);
  /// The tokens of the next line that has any (comments removed); false at the end.
  bool next_line(std::vector<std::string_view>& tokens);
  /// Skips the rest of the current line.
  void skip_line();
  /// The line of the last token returned.
  int line() const { return token_line_; }
  std::size_t position() const { return pos_; }
  std::size_t remaining() const { return text_.size() - pos_; }

 private:
  /// Skips blanks and comments on the current line; true if a line end or the end follows.
  bool at_line_end();
  void take_line_end();

  std::string_view text_;
  std::size_t pos_ = 0;
  int line_;
  int token_line_ = 0;
  char comment_;
};

/// Parses the whole token as an integer (leading '+' accepted).
bool parse_integer(std::string_view token, std::int64_t& value);

/// The text without a UTF-8 byte-order mark.
std::string_view skip_utf8_bom(std::string_view text);

}  // namespace subd2nurbs::mesh_detail
