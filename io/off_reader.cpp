// Reading OFF (io/mesh_reader.h), the Geomview / Princeton shape benchmark format:
//
//   [ST][C][N]OFF [nv nf ne]     the keyword (optional), the counts here or on the next line
//   x y z [values...]            nv vertex lines; values after x y z (colour, normal, texture
//                                coordinates of COFF / NOFF / STOFF ...) are ignored
//   n i0 ... i(n-1) [values...]  nf face lines, 0-based indices; a colour after them is ignored
//
// `#` starts a comment anywhere; blank lines are skipped. The edge count is ignored. 4OFF / nOFF
// (other dimensions) and binary OFF are refused. Counts are checked against the bytes present
// before anything is allocated (a vertex line takes at least 6 bytes, a face line 8).
#include "core/mesh/validate.h"
#include "io/input_file.h"
#include "io/mesh_reader_detail.h"

namespace subd2nurbs {

namespace {

using mesh_detail::quoted;
using mesh_detail::RawMesh;
using mesh_detail::TextCursor;

/// Whether `token` is an OFF keyword ([ST][C][N]OFF); `dimension` is set for 4OFF / nOFF.
bool is_keyword(std::string_view token, bool& dimension) {
  dimension = false;
  auto take = [&](std::string_view prefix) {
    if (token.substr(0, prefix.size()) == prefix) token.remove_prefix(prefix.size());
  };
  take("ST");
  take("C");
  take("N");
  if (!token.empty() && (token[0] == '4' || token[0] == 'n')) {
    dimension = true;
    token.remove_prefix(1);
  }
  return token == "OFF";
}

}  // namespace

LoadedCage parse_off(const std::string& bytes, const std::string& name, const MeshReadOptions& options) {
  TextCursor in(mesh_detail::skip_utf8_bom(bytes), 1, '#');
  std::vector<std::string_view> tokens;
  auto fail = [&](const std::string& message) { return InputError(name, in.line(), message); };
  if (!in.next_line(tokens)) throw InputError(name, 0, "not an OFF file: it is empty");

  // The keyword, then the counts on the same line or the next.
  std::size_t first_count = 0;
  bool dimension = false;
  if (is_keyword(tokens[0], dimension)) {
    if (dimension) throw fail(quoted(tokens[0]) + ": only 3-dimensional OFF is supported");
    if (tokens.size() > 1 && tokens[1] == "BINARY") throw fail("binary OFF is not supported");
    first_count = 1;
    if (tokens.size() == 1) {  // the counts on a line of their own
      if (!in.next_line(tokens)) throw fail("the file ends before the vertex and face counts");
      first_count = 0;
    }
  } else {
    std::int64_t n;
    if (!mesh_detail::parse_integer(tokens[0], n))
      throw fail("not an OFF file: it starts with " + quoted(tokens[0]) + ", not 'OFF' or the counts");
  }
  if (tokens.size() < first_count + 2) throw fail("expected the counts 'vertices faces [edges]'");
  std::int64_t counts[2];
  for (int k = 0; k < 2; ++k)
    if (!mesh_detail::parse_integer(tokens[first_count + static_cast<std::size_t>(k)], counts[k]) || counts[k] < 0)
      throw fail("the " + std::string(k ? "face" : "vertex") + " count " + quoted(tokens[first_count + static_cast<std::size_t>(k)]) +
                 " is not a count");
  const std::int64_t nv = counts[0], nf = counts[1];
  for (std::int64_t n : {nv, nf})
    if (n > options.max_elements)
      throw fail("the file announces " + std::to_string(n) + " " + (n == nv ? "vertices" : "faces") + "; at most " +
                 std::to_string(options.max_elements) + " are read");
  const auto left = static_cast<std::int64_t>(in.remaining());
  if (6 * nv + 8 * nf > left + 14)
    throw fail("the file announces " + std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces, but only " +
               std::to_string(left) + " bytes follow (a vertex line takes at least 6, a face line 8)");

  RawMesh raw;
  raw.positions.reserve(static_cast<std::size_t>(nv));
  raw.vertex_loc.reserve(static_cast<std::size_t>(nv));
  for (std::int64_t v = 0; v < nv; ++v) {
    if (!in.next_line(tokens))
      throw InputError(name, in.line(), "the file ends after " + std::to_string(v) + " of its " + std::to_string(nv) + " vertices");
    if (tokens.size() < 3) throw fail("a vertex line needs 3 coordinates 'x y z'");
    std::array<double, 3> p{};
    for (std::size_t k = 0; k < 3; ++k)
      if (!parse_double(tokens[k], p[k])) throw fail("vertex coordinate " + quoted(tokens[k]) + " is not a number");
    raw.positions.push_back(p);
    raw.vertex_loc.push_back(in.line());
  }
  raw.face_sizes.reserve(static_cast<std::size_t>(nf));
  raw.face_loc.reserve(static_cast<std::size_t>(nf));
  for (std::int64_t f = 0; f < nf; ++f) {
    if (!in.next_line(tokens))
      throw InputError(name, in.line(), "the file ends after " + std::to_string(f) + " of its " + std::to_string(nf) + " faces");
    std::int64_t n = 0;
    if (!mesh_detail::parse_integer(tokens[0], n) || n < 0)
      throw fail("a face line starts with its vertex count, not " + quoted(tokens[0]));
    if (n > kMaxFaceSize)
      throw InputError(name, in.line(), "face has " + std::to_string(n) + " vertices; at most " +
                                            std::to_string(kMaxFaceSize) + " are supported (split it)",
                       MeshErrorCode::FaceTooLarge);
    if (static_cast<std::int64_t>(tokens.size()) < n + 1)
      throw fail("the face announces " + std::to_string(n) + " vertices but " + std::to_string(tokens.size() - 1) +
                 " values follow");
    for (std::int64_t k = 1; k <= n; ++k) {
      std::int64_t index = 0;
      if (!mesh_detail::parse_integer(tokens[static_cast<std::size_t>(k)], index))
        throw fail("face vertex " + quoted(tokens[static_cast<std::size_t>(k)]) + " is not a vertex index");
      raw.face_indices.push_back(index);
    }
    raw.face_sizes.push_back(static_cast<int>(n));
    raw.face_loc.push_back(in.line());
  }
  return mesh_detail::finish_mesh(std::move(raw), name, options);
}

LoadedCage read_off(const std::string& path, const MeshReadOptions& options) {
  return parse_off(read_input_file(path, "an OFF file"), path, options);
}

}  // namespace subd2nurbs
