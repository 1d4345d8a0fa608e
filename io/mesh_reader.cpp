// The repairs every STL, PLY and OFF file goes through (io/mesh_reader.h): checks, welding,
// degenerate and duplicate faces, unused vertices, orientation, quad recovery; and the text
// cursor the ASCII readers share.
#include "core/util/number_text.h"
#include "io/mesh_reader.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "core/mesh/quad_recovery.h"
#include "core/mesh/validate.h"
#include "io/input_file.h"
#include "io/mesh_reader_detail.h"

namespace subd2nurbs::mesh_detail {

// --- text helpers ----------------------------------------------------------------------------

std::string quoted(std::string_view token) { return "'" + printable(token, 60) + "'"; }

bool parse_integer(std::string_view token, std::int64_t& value) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end;
}

std::string_view skip_utf8_bom(std::string_view text) {
  if (text.substr(0, 3) == std::string_view("\xEF\xBB\xBF", 3)) text.remove_prefix(3);
  return text;
}

namespace {
bool is_space(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }
}  // namespace

bool TextCursor::at_line_end() {
  while (pos_ < text_.size() && is_space(text_[pos_])) ++pos_;
  if (pos_ < text_.size() && comment_ != 0 && text_[pos_] == comment_)
    while (pos_ < text_.size() && text_[pos_] != '\n' && text_[pos_] != '\r') ++pos_;
  return pos_ >= text_.size() || text_[pos_] == '\n' || text_[pos_] == '\r';
}

void TextCursor::take_line_end() {
  if (pos_ >= text_.size()) return;
  pos_ += text_.compare(pos_, 2, "\r\n") == 0 ? 2 : 1;
  ++line_;
}

bool TextCursor::next(std::string_view& token) {
  while (at_line_end()) {
    if (pos_ >= text_.size()) return false;
    take_line_end();
  }
  const std::size_t begin = pos_;
  while (pos_ < text_.size() && !is_space(text_[pos_]) && text_[pos_] != '\n' && text_[pos_] != '\r' &&
         !(comment_ != 0 && text_[pos_] == comment_))
    ++pos_;
  token = text_.substr(begin, pos_ - begin);
  token_line_ = line_;
  return true;
}

bool TextCursor::next_line(std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::string_view token;
  if (!next(token)) return false;
  tokens.push_back(token);
  while (!at_line_end()) {
    next(token);
    tokens.push_back(token);
  }
  take_line_end();
  return true;
}

void TextCursor::skip_line() {
  while (pos_ < text_.size() && text_[pos_] != '\n' && text_[pos_] != '\r') ++pos_;
}

// --- locations -------------------------------------------------------------------------------

InputError error_at(const std::string& name, LoadedCage::Locator locator, const std::string& unit, int loc,
                    const std::string& message, std::optional<MeshErrorCode> code) {
  if (locator == LoadedCage::Locator::Line || loc <= 0) return InputError(name, loc, message, code);
  return InputError(name, 0, unit + " " + std::to_string(loc - 1) + ": " + message, code);
}

namespace {

using Point = std::array<double, 3>;

std::string number_text(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", x);
  return buffer;
}

/// Where faces are, for messages: "lines 3, 7, 9" or "facets 2, 6, 8" ("line 3", "facet 2").
std::string face_list(const RawMesh& raw, const std::vector<int>& faces) {
  const bool lines = raw.locator == LoadedCage::Locator::Line;
  std::string s = (lines ? std::string("line") : raw.face_unit) + (faces.size() > 1 ? "s " : " ");
  for (std::size_t i = 0; i < faces.size() && i < 8; ++i) {
    const int loc = raw.face_loc[static_cast<std::size_t>(faces[i])];
    s += (i ? ", " : "") + std::to_string(lines ? loc : loc - 1);
  }
  if (faces.size() > 8) s += ", ...";
  return s;
}

/// Welds positions closer than `tolerance` (the first vertex of a cluster represents it;
/// spatial hashing with cells of the tolerance's size). Returns the welded id per vertex;
/// ids are given in order of the representatives' first appearance. `near` counts the
/// vertices welded onto a representative at a different position.
std::vector<int> weld(const std::vector<Point>& positions, const Point& lower, double tolerance, int& count,
                      int& near) {
  std::vector<int> id(positions.size());
  count = 0;
  near = 0;
  // Cells by their integer coordinates held as doubles (no overflow whatever the ratio of the
  // model's size to the tolerance); tolerance 0: the positions themselves.
  using Cell = std::array<double, 3>;
  struct CellHash {
    std::size_t operator()(const Cell& c) const {
      std::uint64_t h = 1469598103934665603ull;
      for (double x : c) {
        std::uint64_t bits;
        x = x == 0 ? 0.0 : x;  // -0 and +0 in one cell
        std::memcpy(&bits, &x, sizeof bits);
        h = (h ^ bits) * 1099511628211ull;
        h ^= h >> 29;
      }
      return static_cast<std::size_t>(h);
    }
  };
  std::unordered_map<Cell, std::vector<int>, CellHash> grid;  // cell -> representative vertices
  grid.reserve(positions.size());
  std::vector<int> representative;  // welded id -> vertex
  auto cell_of = [&](const Point& p) {
    if (tolerance == 0) return p;
    return Cell{std::floor((p[0] - lower[0]) / tolerance), std::floor((p[1] - lower[1]) / tolerance),
                std::floor((p[2] - lower[2]) / tolerance)};
  };
  const double t2 = tolerance * tolerance;
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const Point& p = positions[v];
    const Cell c = cell_of(p);
    int found = -1;
    const int reach = tolerance == 0 ? 0 : 1;
    for (int dx = -reach; dx <= reach; ++dx)
      for (int dy = -reach; dy <= reach; ++dy)
        for (int dz = -reach; dz <= reach; ++dz) {
          const auto it = grid.find(Cell{c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (int w : it->second) {
            const Point& q = positions[static_cast<std::size_t>(representative[static_cast<std::size_t>(w)])];
            const double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
            if (d2 <= t2 && (found < 0 || w < found)) found = w;
          }
        }
    if (found < 0) {
      found = count++;
      representative.push_back(static_cast<int>(v));
      grid[c].push_back(found);
    } else if (positions[static_cast<std::size_t>(representative[static_cast<std::size_t>(found)])] != p) {
      ++near;
    }
    id[v] = found;
  }
  return id;
}

/// A face as a list of cage vertices, with the file face it comes from.
struct Faces {
  std::vector<int> sizes, indices, offsets{0}, source;
  int count() const { return static_cast<int>(sizes.size()); }
  const int* at(int f) const { return indices.data() + offsets[static_cast<std::size_t>(f)]; }
  void add(const std::vector<int>& face, int from) {
    sizes.push_back(static_cast<int>(face.size()));
    indices.insert(indices.end(), face.begin(), face.end());
    offsets.push_back(static_cast<int>(indices.size()));
    source.push_back(from);
  }
};

/// Makes the faces consistently oriented per connected component, closed components outward.
/// \throw InputError for an edge of three or more faces or a non-orientable component.
void orient(Faces& faces, const std::vector<Point>& positions, const RawMesh& raw, const std::string& name,
            LoadedCage::MeshRepair& repair) {
  const int nf = faces.count();
  struct Half {
    std::uint64_t key;
    int face, local;
  };
  std::vector<Half> halves;
  halves.reserve(faces.indices.size());
  for (int f = 0; f < nf; ++f) {
    const int n = faces.sizes[static_cast<std::size_t>(f)];
    for (int i = 0; i < n; ++i) {
      const auto a = static_cast<std::uint32_t>(faces.at(f)[i]), b = static_cast<std::uint32_t>(faces.at(f)[(i + 1) % n]);
      halves.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), f, i});
    }
  }
  std::sort(halves.begin(), halves.end(),
            [](const Half& x, const Half& y) { return x.key != y.key ? x.key < y.key : x.face < y.face; });
  auto from = [&](const Half& h) { return faces.at(h.face)[h.local]; };
  // Neighbours across edges with two faces: (face, neighbour, same direction).
  struct Link {
    int face, other;
    bool same;
  };
  std::vector<Link> links;
  std::vector<char> has_boundary(static_cast<std::size_t>(nf), 0);
  for (std::size_t i = 0; i < halves.size();) {
    std::size_t j = i;
    while (j < halves.size() && halves[j].key == halves[i].key) ++j;
    if (j - i == 1) {
      has_boundary[static_cast<std::size_t>(halves[i].face)] = 1;
    } else if (j - i == 2) {
      const bool same = from(halves[i]) == from(halves[i + 1]);
      links.push_back({halves[i].face, halves[i + 1].face, same});
      links.push_back({halves[i + 1].face, halves[i].face, same});
    } else {
      std::vector<int> around;
      for (std::size_t k = i; k < j; ++k) around.push_back(faces.source[static_cast<std::size_t>(halves[k].face)]);
      const int culprit = around[2];
      throw error_at(name, raw.locator, raw.face_unit, raw.face_loc[static_cast<std::size_t>(culprit)],
                     "non-manifold edge: shared by " + std::to_string(j - i) + " faces (" + face_list(raw, around) +
                         "); an edge may border at most 2 faces",
                     MeshErrorCode::NonManifoldEdge);
    }
    i = j;
  }
  std::sort(links.begin(), links.end(), [](const Link& x, const Link& y) {
    return x.face != y.face ? x.face < y.face : x.other < y.other;
  });
  std::vector<int> first(static_cast<std::size_t>(nf) + 1, 0);
  for (const Link& l : links) ++first[static_cast<std::size_t>(l.face) + 1];
  for (int f = 0; f < nf; ++f) first[static_cast<std::size_t>(f) + 1] += first[static_cast<std::size_t>(f)];

  // Breadth-first from each face not reached yet, in file order.
  std::vector<int> component(static_cast<std::size_t>(nf), -1);
  std::vector<char> flip(static_cast<std::size_t>(nf), 0);
  std::vector<int> queue;
  for (int seed = 0; seed < nf; ++seed) {
    if (component[static_cast<std::size_t>(seed)] >= 0) continue;
    const int c = repair.components++;
    queue.assign(1, seed);
    component[static_cast<std::size_t>(seed)] = c;
    bool closed = true;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int f = queue[q];
      if (has_boundary[static_cast<std::size_t>(f)]) closed = false;
      for (int k = first[static_cast<std::size_t>(f)]; k < first[static_cast<std::size_t>(f) + 1]; ++k) {
        const Link& l = links[static_cast<std::size_t>(k)];
        const char want = static_cast<char>(flip[static_cast<std::size_t>(f)] ^ (l.same ? 1 : 0));
        if (component[static_cast<std::size_t>(l.other)] < 0) {
          component[static_cast<std::size_t>(l.other)] = c;
          flip[static_cast<std::size_t>(l.other)] = want;
          queue.push_back(l.other);
        } else if (flip[static_cast<std::size_t>(l.other)] != want) {
          const int a = faces.source[static_cast<std::size_t>(f)], b = faces.source[static_cast<std::size_t>(l.other)];
          throw error_at(name, raw.locator, raw.face_unit, raw.face_loc[static_cast<std::size_t>(std::max(a, b))],
                         "the surface is not orientable (like a Moebius strip): this face cannot be oriented "
                         "consistently with all its neighbours (it meets the one on " + face_list(raw, {std::min(a, b)}) +
                             " both ways round)",
                         MeshErrorCode::InconsistentOrientation);
        }
      }
    }
    // Reverse the minority, so the file's orientation is kept where most faces agree.
    std::size_t flipped = 0;
    for (int f : queue) flipped += static_cast<std::size_t>(flip[static_cast<std::size_t>(f)]);
    if (2 * flipped > queue.size()) {
      for (int f : queue) flip[static_cast<std::size_t>(f)] ^= 1;
      flipped = queue.size() - flipped;
    }
    repair.faces_flipped += static_cast<int>(flipped);
    if (!closed) continue;
    ++repair.closed_components;
    // Signed volume (divergence theorem over fan triangles), relative to one of its points.
    const Point& o = positions[static_cast<std::size_t>(faces.at(seed)[0])];
    double volume = 0;
    for (int f : queue) {
      const int* v = faces.at(f);
      const int n = faces.sizes[static_cast<std::size_t>(f)];
      double s = 0;
      for (int i = 1; i + 1 < n; ++i) {
        const Point& a = positions[static_cast<std::size_t>(v[0])];
        const Point& b = positions[static_cast<std::size_t>(v[i])];
        const Point& d = positions[static_cast<std::size_t>(v[i + 1])];
        const Point p{a[0] - o[0], a[1] - o[1], a[2] - o[2]}, q{b[0] - o[0], b[1] - o[1], b[2] - o[2]},
            r{d[0] - o[0], d[1] - o[1], d[2] - o[2]};
        s += p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) + p[2] * (q[0] * r[1] - q[1] * r[0]);
      }
      volume += flip[static_cast<std::size_t>(f)] ? -s : s;
    }
    if (volume < 0) {
      for (int f : queue) flip[static_cast<std::size_t>(f)] ^= 1;
      ++repair.components_reversed;
    }
  }
  // Reverse a face keeping its first vertex: (a, b, c, d) -> (a, d, c, b).
  for (int f = 0; f < nf; ++f) {
    if (!flip[static_cast<std::size_t>(f)]) continue;
    int* v = faces.indices.data() + faces.offsets[static_cast<std::size_t>(f)];
    std::reverse(v + 1, v + faces.sizes[static_cast<std::size_t>(f)]);
  }
}

std::string repair_summary(const LoadedCage::MeshRepair& r) {
  std::string s;
  auto add = [&](int n, const std::string& what) {
    if (n > 0) s += (s.empty() ? "" : ", ") + std::to_string(n) + " " + what;
  };
  // Welding equal positions is what indexed STL needs, not a repair: only near ones count here.
  add(r.vertices_merged_near, "vertices welded onto a different position within the tolerance " +
                                  number_text(r.weld_tolerance) + " (cracks closed)");
  add(r.degenerate_faces, "degenerate faces dropped");
  add(r.duplicate_faces, "duplicate faces dropped");
  add(r.unused_vertices, "unused vertices removed");
  add(r.faces_flipped, "faces flipped to agree with their neighbours");
  add(r.components_reversed, "closed components turned outward");
  return s;
}

}  // namespace

/// The raw mesh's coordinates (finite, within the limit of every cage) and faces (3 ..
/// kMaxFaceSize vertices, indices in range) checked; the faces' offsets into face_indices.
/// \throw InputError naming the element
std::vector<std::size_t> checked_face_offsets(const RawMesh& raw, const std::string& name) {
  const std::size_t nv = raw.positions.size(), nf = raw.face_sizes.size();
  auto face_error = [&](std::size_t f, const std::string& message, MeshErrorCode code) {
    return error_at(name, raw.locator, raw.face_unit, raw.face_loc[f], message, code);
  };
  // Coordinates: finite and within the limit of every cage.
  for (std::size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) {
      const double x = raw.positions[v][static_cast<std::size_t>(k)];
      const std::string axis(1, "xyz"[k]);
      if (!std::isfinite(x))
        throw error_at(name, raw.locator, raw.vertex_unit, raw.vertex_loc[v],
                       "vertex has a non-finite " + axis + " coordinate (" + (std::isnan(x) ? "NaN" : "Inf") + ")",
                       MeshErrorCode::NonFiniteCoordinate);
      if (std::fabs(x) > kMaxCoordinate)
        throw error_at(name, raw.locator, raw.vertex_unit, raw.vertex_loc[v],
                       "vertex has " + axis + " = " + exact_number_text(x) + ", beyond the coordinate limit +-" +
                           number_text(kMaxCoordinate) + " (scale the model down)",
                       MeshErrorCode::CoordinateOutOfRange);
    }
  // Faces: sizes and indices.
  std::vector<std::size_t> offset(nf + 1, 0);
  for (std::size_t f = 0; f < nf; ++f) {
    const int n = raw.face_sizes[f];
    if (n < 3)
      throw face_error(f, "face has " + std::to_string(n) + " vertices; at least 3 are needed", MeshErrorCode::FaceTooSmall);
    if (n > kMaxFaceSize)
      throw face_error(f, "face has " + std::to_string(n) + " vertices; at most " + std::to_string(kMaxFaceSize) +
                              " are supported (split it)",
                       MeshErrorCode::FaceTooLarge);
    offset[f + 1] = offset[f] + static_cast<std::size_t>(n);
    for (std::size_t i = offset[f]; i < offset[f + 1]; ++i) {
      const std::int64_t v = raw.face_indices[i];
      if (v < 0 || v >= static_cast<std::int64_t>(nv))
        throw face_error(f, "face refers to vertex " + std::to_string(v) + ", but the file defines " + std::to_string(nv) +
                                " vertices (0 to " + std::to_string(static_cast<long long>(nv) - 1) + ")",
                         MeshErrorCode::IndexOutOfRange);
    }
  }
  return offset;
}

/// The weld tolerance: options.weld_tolerance of the bounding-box diagonal, at most
/// options.max_weld_edge_fraction of the shortest non-zero edge; 0 when that leaves nothing.
/// `lower`: the bounding box's lower corner (the welding grid's origin).
double weld_tolerance(const RawMesh& raw, const std::vector<std::size_t>& offset, const MeshReadOptions& options,
                      Point& lower) {
  const std::size_t nv = raw.positions.size(), nf = raw.face_sizes.size();
  Point upper{0, 0, 0};
  lower = {0, 0, 0};
  for (std::size_t v = 0; v < nv; ++v)
    for (std::size_t k = 0; k < 3; ++k) {
      lower[k] = v == 0 ? raw.positions[v][k] : std::min(lower[k], raw.positions[v][k]);
      upper[k] = v == 0 ? raw.positions[v][k] : std::max(upper[k], raw.positions[v][k]);
    }
  const double diagonal = std::hypot(upper[0] - lower[0], upper[1] - lower[1], upper[2] - lower[2]);
  double shortest = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < nf; ++f)
    for (std::size_t i = offset[f]; i < offset[f + 1]; ++i) {
      const std::size_t j = i + 1 < offset[f + 1] ? i + 1 : offset[f];
      const Point& a = raw.positions[static_cast<std::size_t>(raw.face_indices[i])];
      const Point& b = raw.positions[static_cast<std::size_t>(raw.face_indices[j])];
      const double length = std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
      if (length > 0) shortest = std::min(shortest, length);
    }
  double tolerance = std::max(0.0, options.weld_tolerance) * diagonal;
  if (std::isfinite(shortest)) tolerance = std::min(tolerance, options.max_weld_edge_fraction * shortest);
  if (!(tolerance > 0) || !std::isfinite(tolerance)) tolerance = 0;
  return tolerance;
}

/// Drops the faces with the vertex set of an earlier face (either orientation), counted in
/// repair.duplicate_faces.
void drop_duplicate_faces(Faces& faces, LoadedCage::MeshRepair& repair) {
  std::vector<int> face;
  {
    std::vector<int> sorted_indices = faces.indices;
    for (int f = 0; f < faces.count(); ++f)
      std::sort(sorted_indices.begin() + faces.offsets[static_cast<std::size_t>(f)],
                sorted_indices.begin() + faces.offsets[static_cast<std::size_t>(f) + 1]);
    std::vector<int> order(static_cast<std::size_t>(faces.count()));
    for (int f = 0; f < faces.count(); ++f) order[static_cast<std::size_t>(f)] = f;
    auto key_less = [&](int a, int b) {
      const auto sa = faces.sizes[static_cast<std::size_t>(a)], sb = faces.sizes[static_cast<std::size_t>(b)];
      if (sa != sb) return sa < sb;
      const int* pa = sorted_indices.data() + faces.offsets[static_cast<std::size_t>(a)];
      const int* pb = sorted_indices.data() + faces.offsets[static_cast<std::size_t>(b)];
      return std::lexicographical_compare(pa, pa + sa, pb, pb + sb);
    };
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      if (key_less(a, b)) return true;
      if (key_less(b, a)) return false;
      return a < b;
    });
    std::vector<char> duplicate(static_cast<std::size_t>(faces.count()), 0);
    for (std::size_t k = 1; k < order.size(); ++k)
      if (!key_less(order[k - 1], order[k])) {
        duplicate[static_cast<std::size_t>(order[k])] = 1;
        ++repair.duplicate_faces;
      }
    if (repair.duplicate_faces > 0) {
      Faces kept;
      for (int f = 0; f < faces.count(); ++f) {
        if (duplicate[static_cast<std::size_t>(f)]) continue;
        face.assign(faces.at(f), faces.at(f) + faces.sizes[static_cast<std::size_t>(f)]);
        kept.add(face, faces.source[static_cast<std::size_t>(f)]);
      }
      faces = std::move(kept);
    }
  }
}

LoadedCage finish_mesh(RawMesh raw, const std::string& name, const MeshReadOptions& options) {
  const std::size_t nv = raw.positions.size(), nf = raw.face_sizes.size();
  auto face_error = [&](std::size_t f, const std::string& message, MeshErrorCode code) {
    return error_at(name, raw.locator, raw.face_unit, raw.face_loc[f], message, code);
  };

  const std::vector<std::size_t> offset = checked_face_offsets(raw, name);

  LoadedCage cage;
  cage.path = name;
  cage.locator = raw.locator;
  cage.face_unit = raw.face_unit;
  cage.vertex_unit = raw.vertex_unit;
  cage.diagnostics = std::move(raw.diagnostics);
  LoadedCage::MeshRepair& repair = cage.repair;
  repair.applied = true;
  repair.file_vertices = static_cast<int>(nv);
  repair.file_faces = static_cast<int>(nf);
  if (nf == 0) {
    if (nv == 0) throw InputError(name, 0, "the file has no vertices and no faces");
    // A point cloud: no cage, but the points are kept (validate_cage refuses it as empty).
    repair.point_cloud = true;
    cage.input.positions = std::move(raw.positions);
    cage.vertex_line = std::move(raw.vertex_loc);
    return cage;
  }

  Point lower{0, 0, 0};
  const double tolerance = weld_tolerance(raw, offset, options, lower);
  repair.weld_tolerance = tolerance;

  int welded_count = 0;
  const std::vector<int> id = weld(raw.positions, lower, tolerance, welded_count, repair.vertices_merged_near);
  repair.vertices_merged = static_cast<int>(nv) - welded_count;

  // Faces on welded vertices: repeats of a vertex in a row removed (an edge collapsed), faces
  // left with fewer than 3 vertices dropped; a vertex repeated apart is an error.
  Faces faces;
  std::vector<int> face;
  for (std::size_t f = 0; f < nf; ++f) {
    face.clear();
    for (std::size_t i = offset[f]; i < offset[f + 1]; ++i) {
      const int w = id[static_cast<std::size_t>(raw.face_indices[i])];
      if (face.empty() || face.back() != w) face.push_back(w);
    }
    while (face.size() > 1 && face.back() == face.front()) face.pop_back();
    if (face.size() < 3) {
      ++repair.degenerate_faces;
      continue;
    }
    std::vector<int> sorted = face;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
      throw face_error(f, "face uses a vertex twice (after welding with tolerance " + number_text(tolerance) +
                              "); such pinched faces are not supported",
                       MeshErrorCode::RepeatedVertexInFace);
    faces.add(face, static_cast<int>(f));
  }
  drop_duplicate_faces(faces, repair);
  if (faces.count() == 0)
    throw InputError(name, 0, "no face is left: all " + std::to_string(nf) +
                                  " faces are degenerate once vertices closer than " + number_text(tolerance) +
                                  " are welded");

  // Vertices no face uses go; the others keep their order of first appearance.
  std::vector<int> compact(static_cast<std::size_t>(welded_count), -1);
  for (int w : faces.indices) compact[static_cast<std::size_t>(w)] = 0;
  std::vector<Point> positions;
  std::vector<int> vertex_loc;
  {
    std::vector<int> first_vertex(static_cast<std::size_t>(welded_count), -1);
    for (std::size_t v = nv; v-- > 0;) first_vertex[static_cast<std::size_t>(id[v])] = static_cast<int>(v);
    for (int w = 0; w < welded_count; ++w) {
      if (compact[static_cast<std::size_t>(w)] < 0) {
        ++repair.unused_vertices;
        continue;
      }
      compact[static_cast<std::size_t>(w)] = static_cast<int>(positions.size());
      const auto v = static_cast<std::size_t>(first_vertex[static_cast<std::size_t>(w)]);
      positions.push_back(raw.positions[v]);
      vertex_loc.push_back(raw.vertex_loc[v]);
    }
  }
  for (int& w : faces.indices) w = compact[static_cast<std::size_t>(w)];

  orient(faces, positions, raw, name, repair);

  MeshInput mesh;
  mesh.positions = std::move(positions);
  mesh.face_sizes = faces.sizes;
  mesh.face_indices = faces.indices;
  repair.triangles_only = std::all_of(raw.face_sizes.begin(), raw.face_sizes.end(), [](int n) { return n == 3; });
  cage.vertex_line = std::move(vertex_loc);
  if (repair.triangles_only && options.recover_quads) {
    QuadRecoveryResult r = recover_quads(mesh);
    for (const std::vector<int>& s : r.sources)
      cage.face_line.push_back(raw.face_loc[static_cast<std::size_t>(faces.source[static_cast<std::size_t>(s[0])])]);
    take_recovered_quads(cage, std::move(r));
  } else {
    cage.input = std::move(mesh);
    for (int s : faces.source) cage.face_line.push_back(raw.face_loc[static_cast<std::size_t>(s)]);
  }
  const std::string summary = repair_summary(repair);
  if (!summary.empty()) cage.diagnostics.push_back({"mesh-repair", ElementKind::None, 0, "repaired: " + summary});
  return cage;
}

}  // namespace subd2nurbs::mesh_detail

namespace subd2nurbs {

void take_recovered_quads(LoadedCage& cage, QuadRecoveryResult&& result) {
  cage.input = std::move(result.mesh);
  cage.recovery.applied = true;
  cage.recovery.source_triangles = result.input_triangles;
  cage.recovery.quads = result.quads;
  cage.recovery.triangles_kept = result.triangles_kept;
  cage.recovery.fan_vertices = result.fan_vertices;
  cage.recovery.fan_triangles = result.fan_triangles;
}

}  // namespace subd2nurbs
