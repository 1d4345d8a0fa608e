// OBJ reading in two passes over the same in-memory text:
//
//  1. Our own line scan records the line of every vertex, face and tag, parses coordinates
//     and tags, and rejects what tinyobjloader would silently change: faces with fewer than
//     3 vertices (dropped), vertex index 0 (a parse failure without a usable location) and
//     malformed numbers. Coordinates are taken from this pass: tinyobjloader's own number
//     parser (2.0.0rc10) is not correctly rounded (e.g. "-0.012886" comes back one ulp off,
//     which breaks bit-exact round trips) and reads "nan" / "inf" as 0.
//  2. tinyobjloader (triangulate=false) resolves the face index lists (a/t/n forms, negative
//     relative indices). Its shapes hold the faces in file order; we concatenate them and check
//     that they agree with pass 1 face by face.
#include "core/mesh/poly_mesh.h"
#include "core/util/number_text.h"
#include "io/obj_reader.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>

#include "core/mesh/validate.h"
#include "io/input_file.h"
#include "io/mesh_reader_detail.h"

namespace subd2nurbs {

namespace {

// --- text helpers ----------------------------------------------------------------------------

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::vector<std::string_view> split_tokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i])) ++i;
    const size_t begin = i;
    while (i < line.size() && !is_blank(line[i])) ++i;
    if (i > begin) tokens.push_back(line.substr(begin, i - begin));
  }
  return tokens;
}

/// Parses the whole token as an int (leading '+' accepted).
bool parse_int(std::string_view token, int& value) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end;
}

/// A token of the file for a message: quoted, printable and shortened (io/input_file.h).
std::string quoted(std::string_view s) { return "'" + printable(s, 60) + "'"; }

/// The text without a UTF-8 byte-order mark (which would make the first statement unknown
/// and shift every face index). UTF-16 and UTF-32 are refused: OBJ is ASCII.
std::string strip_byte_order_mark(const std::string& text, const std::string& path) {
  auto starts_with = [&](std::string_view prefix) { return text.compare(0, prefix.size(), prefix) == 0; };
  using namespace std::string_view_literals;
  if (starts_with("\xEF\xBB\xBF"sv)) return text.substr(3);
  if (starts_with("\x00\x00\xFE\xFF"sv) || starts_with("\xFF\xFE\x00\x00"sv))
    throw InputError(path, 1, "the file is UTF-32 encoded; OBJ files must be ASCII or UTF-8");
  if (starts_with("\xFE\xFF"sv) || starts_with("\xFF\xFE"sv))
    throw InputError(path, 1, "the file is UTF-16 encoded (byte-order mark); OBJ files must be ASCII or UTF-8");
  // UTF-16 without a byte-order mark: every other byte of ASCII text is NUL.
  if (text.size() >= 4 && ((text[0] == '\0') != (text[1] == '\0')) &&
      ((text[2] == '\0') != (text[3] == '\0')))
    throw InputError(path, 1, "the file looks UTF-16 encoded (NUL bytes between the characters); "
                              "OBJ files must be ASCII or UTF-8");
  return text;
}

// --- pass 1: the line scan ---------------------------------------------------------------

/// Statements that are valid OBJ but carry nothing a cage needs.
const std::set<std::string_view> kIgnoredStatements = {"vt", "vn", "vp", "g", "o", "s",
                                                       "usemtl", "mtllib"};
/// Tags of the OpenSubdiv format that this reader does not apply.
const std::set<std::string_view> kUnsupportedTags = {
    "vertexedit", "edgeedit", "faceedit", "facevaryinginterpolateboundary",
    "facevaryingpropagatecorners", "propagatecorners"};

class LineScanner {
 public:
  explicit LineScanner(LoadedCage& cage) : cage_(cage) {}

  /// Scans the text; face vertex counts go to cage.input.face_sizes, the index lists are
  /// left to pass 2.
  void scan(const std::string& text) {
    size_t pos = 0;
    int number = 0;
    while (pos < text.size()) {
      // Line ends as tinyobjloader sees them: "\n", "\r\n" or a lone "\r".
      size_t end = text.find_first_of("\r\n", pos);
      if (end == std::string::npos) end = text.size();
      line_ = ++number;
      statement(std::string_view(text).substr(pos, end - pos));
      pos = end;
      if (pos < text.size()) pos += text.compare(pos, 2, "\r\n") == 0 ? 2 : 1;
    }
  }

 private:
  [[noreturn]] void error(const std::string& message,
                          std::optional<MeshErrorCode> code = std::nullopt) const {
    throw InputError(cage_.path, line_, message, code);
  }
  [[noreturn]] void tag_error(std::string_view tag, const std::string& message) const {
    error("malformed " + quoted(tag) + " tag: " + message, MeshErrorCode::InvalidTag);
  }
  void warn(const std::string& code, const std::string& message) {
    cage_.diagnostics.push_back({code, ElementKind::None, line_, message});
  }

  void statement(std::string_view line) {
    const std::vector<std::string_view> tokens = split_tokens(line);
    if (tokens.empty() || tokens[0][0] == '#') return;
    const std::string_view keyword = tokens[0];
    if (keyword == "v") return vertex(tokens);
    if (keyword == "f") return face(tokens);
    if (keyword == "t") return tag(tokens);
    if (kIgnoredStatements.count(keyword)) return;
    // Warn once per kind of statement, not once per line.
    if (!warned_statements_.insert(std::string(keyword)).second) return;
    if (keyword == "l" || keyword == "p")
      warn("ignored-element", "line and point elements ('" + std::string(keyword) +
                                  "') are not part of a cage and were ignored");
    else
      warn("unknown-statement", "unknown statement " + quoted(keyword) +
                                    " ignored (further occurrences are not reported)");
  }

  void vertex(const std::vector<std::string_view>& tokens) {
    if (tokens.size() < 4) error("a vertex needs 3 coordinates ('v x y z')");
    std::array<double, 3> p{};
    for (int k = 0; k < 3; ++k)
      if (!parse_double(tokens[k + 1], p[k]))
        error("vertex coordinate " + quoted(tokens[k + 1]) + " is not a number");
    // Non-finite values are kept: validation reports them as NonFiniteCoordinate.
    cage_.input.positions.push_back(p);
    cage_.vertex_line.push_back(line_);
  }

  /// A face corner "v", "v/t", "v//n" or "v/t/n" (nonzero integers). Checked here so that
  /// tinyobjloader, which fails without a usable location, never sees a bad one.
  void check_face_corner(std::string_view token) {
    std::string_view parts[3];
    int count = 0;
    for (std::string_view rest = token;; ++count) {
      const size_t slash = rest.find('/');
      if (count == 3) error("face vertex " + quoted(token) + " has more than 3 '/' fields");
      parts[count] = rest.substr(0, slash);
      if (slash == std::string_view::npos) break;
      rest.remove_prefix(slash + 1);
    }
    int index = 0;
    if (!parse_int(parts[0], index))
      error("face vertex " + quoted(token) + " is not a vertex index");
    if (index == 0)
      error("face uses vertex index 0; OBJ indices start at 1", MeshErrorCode::IndexOutOfRange);
    for (int k = 1; k <= count; ++k) {
      const bool may_be_empty = k == 1 && count == 2;  // "v//n"
      if (parts[k].empty() && may_be_empty) continue;
      if (!parse_int(parts[k], index) || index == 0)
        error("face vertex " + quoted(token) + " has an invalid texture or normal index");
    }
  }

  void face(const std::vector<std::string_view>& tokens) {
    const int size = static_cast<int>(tokens.size()) - 1;
    for (int k = 1; k <= size; ++k) check_face_corner(tokens[k]);
    if (size < 3)
      error("face has " + std::to_string(size) + " vertices; at least 3 are needed",
            MeshErrorCode::FaceTooSmall);
    cage_.input.face_sizes.push_back(size);
    cage_.face_line.push_back(line_);
  }

  // "t name nint/nfloat/nstring ints... floats... strings..."
  void tag(const std::vector<std::string_view>& tokens) {
    if (tokens.size() < 2) error("a tag needs a name ('t name nint/nfloat/nstring ...')");
    const std::string_view name = tokens[1];
    const bool supported = name == "crease" || name == "corner" || name == "hole" ||
                           name == "interpolateboundary" || name == "creasemethod" ||
                           name == "smoothtriangles";
    if (!supported) {
      const char* what = kUnsupportedTags.count(name) ? "is not supported" : "is unknown";
      warn("unsupported-tag", "tag " + quoted(name) + " " + what + " and was ignored");
      return;
    }

    if (tokens.size() < 3) tag_error(name, "the argument counts 'nint/nfloat/nstring' are missing");
    int counts[3];
    {
      std::string_view rest = tokens[2];
      for (int k = 0; k < 3; ++k) {
        const size_t slash = k < 2 ? rest.find('/') : std::string_view::npos;
        if (k < 2 && slash == std::string_view::npos)
          tag_error(name, "argument counts " + quoted(tokens[2]) + " are not 'nint/nfloat/nstring'");
        if (!parse_int(rest.substr(0, slash), counts[k]) || counts[k] < 0)
          tag_error(name, "argument counts " + quoted(tokens[2]) + " are not 'nint/nfloat/nstring'");
        if (k < 2) rest.remove_prefix(slash + 1);
      }
    }
    const size_t given = tokens.size() - 3;
    const size_t expected = static_cast<size_t>(counts[0]) + counts[1] + counts[2];
    if (given != expected)
      tag_error(name, quoted(tokens[2]) + " announces " + std::to_string(expected) +
                          " arguments but " + std::to_string(given) + " follow");

    std::vector<int> ints(counts[0]);
    std::vector<double> floats(counts[1]);
    std::vector<std::string_view> strings(tokens.begin() + 3 + counts[0] + counts[1], tokens.end());
    for (int k = 0; k < counts[0]; ++k)
      if (!parse_int(tokens[3 + k], ints[k]))
        tag_error(name, "integer argument " + quoted(tokens[3 + k]) + " is not an integer");
    for (int k = 0; k < counts[1]; ++k)
      if (!parse_double(tokens[3 + counts[0] + k], floats[k]))
        tag_error(name, "float argument " + quoted(tokens[3 + counts[0] + k]) + " is not a number");

    auto expect_counts = [&](bool ok, const char* wanted) {
      if (!ok) tag_error(name, std::string("expected ") + wanted + ", got " + quoted(tokens[2]));
    };
    SubdivOptions& options = cage_.input.options;
    if (name == "crease") {
      const int n = counts[0];
      expect_counts(n >= 2 && counts[2] == 0 && (counts[1] == 1 || counts[1] == n - 1),
                    "k/1/0 or k/(k-1)/0 with k >= 2 (a chain of vertices and its sharpness)");
      for (int k = 0; k + 1 < n; ++k) {
        cage_.input.creases.push_back({ints[k], ints[k + 1], floats[counts[1] == 1 ? 0 : k]});
        cage_.crease_line.push_back(line_);
      }
    } else if (name == "corner") {
      const int n = counts[0];
      expect_counts(n >= 1 && counts[2] == 0 && (counts[1] == 1 || counts[1] == n),
                    "k/1/0 or k/k/0 with k >= 1 (vertices and their sharpness)");
      for (int k = 0; k < n; ++k) {
        cage_.input.corners.push_back({ints[k], floats[counts[1] == 1 ? 0 : k]});
        cage_.corner_line.push_back(line_);
      }
    } else if (name == "hole") {
      expect_counts(counts[0] >= 1 && counts[1] == 0 && counts[2] == 0, "k/0/0 with k >= 1 (faces)");
      for (int f : ints) {
        cage_.input.holes.push_back(f);
        cage_.hole_line.push_back(line_);
      }
    } else if (name == "interpolateboundary") {
      expect_counts(counts[0] == 1 && counts[1] == 0 && counts[2] == 0, "1/0/0");
      switch (ints[0]) {
        case 0: options.boundary = BoundaryRule::None; break;
        case 1: options.boundary = BoundaryRule::EdgeAndCorner; break;
        case 2: options.boundary = BoundaryRule::EdgeOnly; break;
        default:
          tag_error(name, "value " + std::to_string(ints[0]) +
                              " is not 0 (none), 1 (edge and corner) or 2 (edge only)");
      }
    } else if (name == "creasemethod") {
      expect_counts(counts[0] == 0 && counts[1] == 0 && counts[2] == 1, "0/0/1");
      if (strings[0] == "normal") options.crease_method = CreaseMethod::Uniform;
      else if (strings[0] == "chaikin") options.crease_method = CreaseMethod::Chaikin;
      else tag_error(name, "value " + quoted(strings[0]) + " is not 'normal' or 'chaikin'");
    } else if (name == "smoothtriangles") {
      expect_counts(counts[0] == 0 && counts[1] == 0 && counts[2] == 1, "0/0/1");
      if (strings[0] == "catmark") options.triangles = TriangleRule::Catmark;
      else if (strings[0] == "smooth") options.triangles = TriangleRule::Smooth;
      else tag_error(name, "value " + quoted(strings[0]) + " is not 'catmark' or 'smooth'");
    }
  }

  LoadedCage& cage_;
  int line_ = 0;
  std::set<std::string> warned_statements_;
};

// --- pass 2: face indices from tinyobjloader ----------------------------------------------

void read_face_indices(const std::string& text, LoadedCage& cage) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = false;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  // Materials are not needed: an empty material text makes "mtllib" harmless.
  if (!reader.ParseFromString(text, "", config))
    throw InputError(cage.path, 0, "OBJ parser (tinyobjloader) failed: " + reader.Error());

  // Relative indices count the vertices defined so far: both passes must see the same ones.
  if (reader.GetAttrib().vertices.size() / 3 != cage.input.positions.size())
    throw InputError(cage.path, 0,
                     "internal error: tinyobjloader found " +
                         std::to_string(reader.GetAttrib().vertices.size() / 3) +
                         " vertices, the line scan " + std::to_string(cage.input.positions.size()));

  const std::vector<int>& sizes = cage.input.face_sizes;
  std::vector<int>& indices = cage.input.face_indices;
  indices.clear();
  size_t face = 0;
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    const tinyobj::mesh_t& mesh = shape.mesh;
    size_t offset = 0;
    for (unsigned char stored : mesh.num_face_vertices) {
      // num_face_vertices is an unsigned char: a face with more than 255 vertices is stored
      // with its size modulo 256, but its indices are all there. Take the size from pass 1.
      if (face >= sizes.size() || stored != static_cast<unsigned char>(sizes[face]) ||
          offset + sizes[face] > mesh.indices.size())
        throw InputError(cage.path, face < cage.face_line.size() ? cage.face_line[face] : 0,
                         "internal error: tinyobjloader and the line scan disagree about "
                         "face " + std::to_string(face + 1));
      for (int k = 0; k < sizes[face]; ++k) indices.push_back(mesh.indices[offset + k].vertex_index);
      offset += sizes[face];
      ++face;
    }
  }
  if (face != sizes.size())
    throw InputError(cage.path, 0,
                     "internal error: tinyobjloader found " + std::to_string(face) +
                         " faces, the line scan " + std::to_string(sizes.size()));
}

// --- validation errors -> file lines --------------------------------------------------------

int line_at(const std::vector<int>& lines, long index) {
  return index >= 0 && index < static_cast<long>(lines.size()) ? lines[index] : 0;
}

/// Vertices as the user sees them in 'f' lines (1-based).
std::string obj_vertex(long v) { return "vertex " + std::to_string(v + 1); }

/// A cage vertex for a message: OBJ's number; a mesh reader's cage vertices are welded and
/// renumbered, so there the location (line or element) alone names it.
std::string vertex_name(const LoadedCage& cage, long v) { return cage.repair.applied ? "vertex" : obj_vertex(v); }

/// Where an error is: a line, or with Locator::Element the element number and its unit.
struct Where {
  Where(int line) : loc(line) {}  // NOLINT: a plain line converts
  Where(int l, const std::string& u) : loc(l), unit(&u) {}
  int loc;
  const std::string* unit = nullptr;
};

/// Faces that use vertex `a`, and also vertex `b` as a neighbour if b >= 0 (faces along
/// edge a-b), in file order.
std::vector<int> faces_around(const MeshInput& input, long a, long b = -1) {
  std::vector<int> faces;
  for (int f = 0, offset = 0; f < input.num_faces(); offset += input.face_sizes[f++]) {
    const int n = input.face_sizes[f];
    for (int k = 0; k < n; ++k) {
      if (input.face_indices[offset + k] != a) continue;
      const int next = input.face_indices[offset + (k + 1) % n];
      const int prev = input.face_indices[offset + (k + n - 1) % n];
      if (b < 0 || next == b || prev == b) {
        faces.push_back(f);
        break;
      }
    }
  }
  return faces;
}

/// "lines 3, 7, 9", or "facets 2, 6, 8" for Locator::Element (the file's 0-based numbers).
std::string line_list(const LoadedCage& cage, const std::vector<int>& faces) {
  const bool lines = cage.locator == LoadedCage::Locator::Line;
  std::string s = lines ? "lines " : cage.face_unit + "s ";
  const size_t shown = std::min<size_t>(faces.size(), 8);
  for (size_t i = 0; i < shown; ++i)
    s += (i ? ", " : "") + std::to_string(line_at(cage.face_line, faces[i]) - (lines ? 0 : 1));
  if (shown < faces.size()) s += ", ...";
  return s;
}

enum class TagList { Crease, Corner, Hole };

/// validate_and_build checks crease, then corner, then hole tags, but a Tag error's index does
/// not say which list it refers to. Re-validating with the later lists removed tells.
TagList failing_tag_list(const MeshInput& input) {
  auto fails_on_tags = [](const MeshInput& probe) {
    try {
      validate_and_build(probe);
    } catch (const InvalidMeshError& e) {
      return e.element() == ElementKind::Tag;
    }
    return false;
  };
  MeshInput probe = input;
  probe.corners.clear();
  probe.holes.clear();
  if (fails_on_tags(probe)) return TagList::Crease;
  probe.corners = input.corners;
  if (fails_on_tags(probe)) return TagList::Corner;
  return TagList::Hole;
}

bool valid_sharpness(double s) { return std::isfinite(s) && s >= 0; }

std::string sharpness_text(double s) {
  std::ostringstream out;
  out << s;
  return out.str();
}

InputError locate(const LoadedCage& cage, const InvalidMeshError& e) {
  const MeshInput& in = cage.input;
  const MeshErrorCode code = e.code();
  auto at = [&](const Where& where, const std::string& message) {
    if (where.unit) return mesh_detail::error_at(cage.path, cage.locator, *where.unit, where.loc, message, code);
    return InputError(cage.path, where.loc, message, code);
  };
  auto vertex_at = [&](long v) { return Where(line_at(cage.vertex_line, v), cage.vertex_unit); };
  auto face_at = [&](long f) { return Where(line_at(cage.face_line, f), cage.face_unit); };
  switch (code) {
    case MeshErrorCode::EmptyMesh:
      return at(0, "the file defines no mesh (" + std::to_string(in.num_vertices()) +
                       " vertices, " + std::to_string(in.num_faces()) + " faces)");
    case MeshErrorCode::NonFiniteCoordinate:
      return at(vertex_at(e.index()),
                vertex_name(cage, e.index()) + " has a non-finite " +
                    (e.index2() >= 0 && e.index2() < 3 ? std::string(1, "xyz"[e.index2()]) + " " : "") +
                    "coordinate");
    case MeshErrorCode::CoordinateOutOfRange: {
      const int axis = e.index2() >= 0 && e.index2() < 3 ? static_cast<int>(e.index2()) : 0;
      return at(vertex_at(e.index()),
                vertex_name(cage, e.index()) + " has " + "xyz"[axis] + " = " +
                    exact_number_text(in.positions.at(static_cast<size_t>(e.index()))[axis]) +
                    ", beyond the coordinate limit +-" + sharpness_text(kMaxCoordinate) +
                    " (scale the model down)");
    }
    case MeshErrorCode::FaceTooLarge:
      return at(face_at(e.index()),
                "face has " + std::to_string(e.index2()) + " vertices; at most " +
                    std::to_string(kMaxFaceSize) + " are supported (split it)");
    case MeshErrorCode::ValenceTooHigh:
      return at(vertex_at(e.index()),
                vertex_name(cage, e.index()) + " has valence " + std::to_string(e.index2()) + "; at most " +
                    std::to_string(kMaxValence) + " is supported");
    case MeshErrorCode::FaceTooSmall:  // read_obj reports these itself; kept for hand-made cages
      return at(face_at(e.index()),
                "face has " + std::to_string(line_at(in.face_sizes, e.index())) +
                    " vertices; at least 3 are needed");
    case MeshErrorCode::IndexOutOfRange:
      return at(face_at(e.index()),
                e.index2() < 0 ? "face refers to a vertex before the first one (relative index "
                                 "too large)"
                               : "face refers to " + vertex_name(cage, e.index2()) + ", but the file defines " +
                                     std::to_string(in.num_vertices()) + " vertices");
    case MeshErrorCode::RepeatedVertexInFace:
      return at(face_at(e.index()),
                "face uses " + vertex_name(cage, e.index2()) +
                    " twice; such degenerate (non-manifold) faces are not supported");
    case MeshErrorCode::NonManifoldEdge: {
      const std::vector<int> faces = faces_around(in, e.index(), e.index2());
      // Point at the first face beyond the two an edge may have.
      const int culprit = faces.size() > 2 ? faces[2] : -1;
      return at(face_at(culprit),
                "non-manifold edge " + std::to_string(e.index() + 1) + "-" +
                    std::to_string(e.index2() + 1) + ": shared by " +
                    std::to_string(faces.size()) + " faces (" +
                    line_list(cage, faces) + "); an edge may border at most 2 faces");
    }
    case MeshErrorCode::InconsistentOrientation: {
      const long later = std::max(e.index(), e.index2()), earlier = std::min(e.index(), e.index2());
      if (!faces_orientable(in.face_sizes, in.face_indices))
        return at(face_at(later),
                  "the surface is not orientable (like a Moebius strip or a Klein bottle): this face and its "
                  "neighbour on line " + std::to_string(line_at(cage.face_line, earlier)) +
                      " traverse their shared edge in the same direction, and no reversal of faces mends "
                      "that; it cannot be converted to a closed oriented body");
      return at(face_at(later),
                "face is oriented inconsistently with its neighbour on line " +
                    std::to_string(line_at(cage.face_line, earlier)) +
                    " (both traverse their shared edge in the same direction); reverse one of them");
    }
    case MeshErrorCode::NonManifoldVertex:
      return at(vertex_at(e.index()),
                vertex_name(cage, e.index()) + " is non-manifold: its faces (" +
                    line_list(cage, faces_around(in, e.index())) +
                    ") do not form a single connected fan");
    case MeshErrorCode::InvalidTag: {
      const long i = e.index();
      switch (failing_tag_list(in)) {
        case TagList::Crease: {
          const CreaseTag& c = in.creases.at(i);
          return at(line_at(cage.crease_line, i),
                    valid_sharpness(c.sharpness)
                        ? "crease names edge (" + std::to_string(c.v0) + ", " + std::to_string(c.v1) +
                              "), which is not an edge of the mesh (tag indices are 0-based)"
                        : "crease has invalid sharpness " + sharpness_text(c.sharpness));
        }
        case TagList::Corner: {
          const CornerTag& c = in.corners.at(i);
          return at(line_at(cage.corner_line, i),
                    valid_sharpness(c.sharpness)
                        ? "corner names vertex " + std::to_string(c.vertex) + ", but the mesh has " +
                              std::to_string(in.num_vertices()) + " vertices (tag indices are 0-based)"
                        : "corner has invalid sharpness " + sharpness_text(c.sharpness));
        }
        case TagList::Hole:
          return at(line_at(cage.hole_line, i),
                    "hole names face " + std::to_string(in.holes.at(i)) + ", but the mesh has " +
                        std::to_string(in.num_faces()) + " faces (tag indices are 0-based)");
      }
      break;
    }
  }
  // Not expected: keep the core's own message.
  return at(0, e.what());
}

}  // namespace

LoadedCage parse_obj(const std::string& text, const std::string& name) {
  LoadedCage cage;
  cage.path = name;
  const std::string body = strip_byte_order_mark(text, name);
  LineScanner(cage).scan(body);
  read_face_indices(body, cage);
  return cage;
}

LoadedCage read_obj(const std::string& path) { return parse_obj(read_input_file(path, "an OBJ file"), path); }

PolyMesh validate_cage(const LoadedCage& cage, Diagnostics* diagnostics) {
  try {
    return validate_and_build(cage.input, diagnostics);
  } catch (const InvalidMeshError& e) {
    throw locate(cage, e);
  }
}

int source_line(const LoadedCage& cage, const Diagnostic& diagnostic) {
  if (cage.locator == LoadedCage::Locator::Element && diagnostic.element != ElementKind::None) return 0;
  switch (diagnostic.element) {
    case ElementKind::None: return diagnostic.index > 0 ? static_cast<int>(diagnostic.index) : 0;
    case ElementKind::Vertex: return line_at(cage.vertex_line, diagnostic.index);
    case ElementKind::Face: return line_at(cage.face_line, diagnostic.index);
    case ElementKind::Edge:
    case ElementKind::Tag: return 0;
  }
  return 0;
}

std::string format_diagnostic(const LoadedCage& cage, const Diagnostic& diagnostic) {
  const int line = source_line(cage, diagnostic);
  std::string message = diagnostic.message;
  // Validation messages ("vertex 4 is ...": unused-vertex, concave-corner) count vertices from 0;
  // say which vertex the user sees.
  const std::string zero_based = "vertex " + std::to_string(diagnostic.index) + " ";
  if (diagnostic.element == ElementKind::Vertex && message.rfind(zero_based, 0) == 0)
    message = vertex_name(cage, diagnostic.index) + " " + message.substr(zero_based.size());
  return cage.path + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": warning: " +
         message;
}

}  // namespace subd2nurbs
