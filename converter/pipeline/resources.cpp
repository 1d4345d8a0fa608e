#include "converter/pipeline/resources.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <set>
#include <utility>

#include "converter/pipeline/text.h"
#include "core/eval/deviation.h"
#include "core/polar/polar_structure.h"
#include "core/util/vec3.h"
#include "io/input_file.h"

namespace subd2nurbs::pipeline {

double default_max_memory() {
  double physical = 0;
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) physical = static_cast<double>(pages) * static_cast<double>(page);
  double limit = physical > 0 ? physical : 4.0 * (1 << 30);
  for (int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    struct rlimit r;
    if (::getrlimit(resource, &r) == 0 && r.rlim_cur != RLIM_INFINITY)
      limit = std::min(limit, static_cast<double>(r.rlim_cur));
  }
  return std::max(0.75 * limit, 256.0 * (1 << 20));
}

std::string bytes_text(double bytes) {
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB"};
  int u = 0;
  while (bytes >= 1024 && u < 5) {
    bytes /= 1024;
    ++u;
  }
  return short_number(bytes) + " " + units[u];
}

bool parse_memory_size(const std::string& text, double& bytes) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  if (end == begin) return false;
  std::string suffix(end);
  for (char& c : suffix) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  double scale = 1;
  if (!suffix.empty() && std::string("KMGT").find(suffix[0]) != std::string::npos) {
    scale = std::pow(1024.0, 1 + static_cast<int>(std::string("KMGT").find(suffix[0])));
    suffix.erase(0, 1);
    if (suffix == "I" || suffix == "IB" || suffix == "B") suffix.clear();
  } else if (suffix == "B") {
    suffix.clear();
  }
  if (!suffix.empty() || !(value > 0) || !std::isfinite(value * scale)) return false;
  bytes = value * scale;
  return true;
}

std::string time_class(double seconds) {
  if (seconds < 1) return "under a second";
  if (seconds < 10) return "seconds";
  if (seconds < 60) return "tens of seconds";
  if (seconds < 600) return "minutes";
  return "ten minutes or more";
}

namespace {

/// The part of the estimate that the fans' levels do not change: the coarse quads, the semi-sharp
/// edges, the exported faces and the process; and the fans the topology predicts.
struct CageCost {
  double quads = 0;            ///< of the coarsest all-quad level
  double irregular_quads = 0;  ///< of those, the quads with an irregular corner (a patch and a face each)
  double semi_pieces = 0, semi_poles = 0;
  double caps = 0, cap_poles = 0;  ///< polar caps: one face each
  double cap_valence2 = 0;         ///< sum of the caps' valence^2
  std::vector<FanCost> fans;   ///< valence and quads at each irregular vertex; levels 2
};

/// Is coarse vertex v a fan of the patch builder (an extraordinary vertex)? Interior: valence
/// other than 4; boundary: other than 2 faces (valence 3) or a corner's single face.
bool irregular_vertex(const PolyMesh& m, int v) {
  const int f = m.vertex_face_count(v);
  if (f == 0) return false;
  return m.is_boundary_vertex(v) ? f > 2 : f != 4;
}

/// Are the points of these faces on one plane (within 1e-9 of their spread)? The plane's normal
/// is the sum of the faces' Newell normals.
bool flat_faces(const PolyMesh& m, const std::vector<Point3>& x, const std::vector<int>& faces) {
  using namespace vec3;
  Point3 normal{0, 0, 0}, centre{0, 0, 0};
  int count = 0;
  for (int f : faces)
    for (int h = m.face_begin(f); h < m.face_end(f); ++h) {
      const int next = h + 1 < m.face_end(f) ? h + 1 : m.face_begin(f);
      normal = axpy(normal, 1.0, cross(x[m.corner_vertex(h)], x[m.corner_vertex(next)]));
      centre = axpy(centre, 1.0, x[m.corner_vertex(h)]);
      ++count;
    }
  if (count == 0) return true;
  centre = {centre[0] / count, centre[1] / count, centre[2] / count};
  const double nn = norm(normal);
  double spread = 0, off = 0;
  for (int f : faces)
    for (int h = m.face_begin(f); h < m.face_end(f); ++h) {
      const Point3 d = sub(x[m.corner_vertex(h)], centre);
      spread = std::max(spread, norm(d));
      if (nn > 0) off = std::max(off, std::abs(dot(d, normal)) / nn);
    }
  return nn > 0 && off <= 1e-9 * spread;
}

/// The faces touching any corner of `faces` (the faces and their ring): a fan is flat when its
/// limit is, which its ring's faces decide too (a prism's flat 1000-gon cap is curved near the rim).
std::vector<int> with_ring(const PolyMesh& m, const std::vector<int>& faces) {
  std::set<int> out(faces.begin(), faces.end());
  for (int f : faces)
    for (int h = m.face_begin(f); h < m.face_end(f); ++h) {
      const int v = m.corner_vertex(h);
      for (int i = 0; i < m.vertex_face_count(v); ++i) out.insert(m.corner_face(m.vertex_corners(v)[i]));
    }
  return {out.begin(), out.end()};
}

CageCost cage_cost(const SubdivLevel& base, bool polar, const std::vector<Point3>* x) {
  const PolyMesh& m = base.mesh;
  CageCost c;
  std::vector<char> irregular(m.num_vertices(), 0), pole(m.num_vertices(), 0), in_cap(m.num_faces(), 0);
  // A polar structure is one cap patch (docs/math.md 4): no fan at its pole, its triangles'
  // quads one face.
  if (polar)
    for (const PolarStructure& s : detect_polar_structures(base).structures) {
      pole[s.pole] = 1;
      for (int f : s.cap_faces) in_cap[f] = 1;
      c.caps += 1;
      c.cap_poles += 16.0 * s.valence;
      c.cap_valence2 += static_cast<double>(s.valence) * s.valence;
    }
  // The coarse level: the cage when every face outside the caps is a quad, else level 1.
  bool quads = true;
  double corners = 0, quad_faces = 0;
  for (int f = 0; f < m.num_faces(); ++f)
    if (!in_cap[f]) {
      quads = quads && m.face_size(f) == 4;
      corners += m.face_size(f);
      quad_faces += 1;
    }
  c.quads = quads ? quad_faces : corners;
  std::vector<int> irregular_valence(m.num_vertices(), 0);
  for (int v = 0; v < m.num_vertices(); ++v)
    if (!pole[v] && irregular_vertex(m, v)) irregular[v] = 1, irregular_valence[v] = m.valence(v);
  // The fans, with the valences of the irregular vertices next to them at the coarse level:
  // on an all-quad cage the irregular vertices sharing a face; at level 1 a cage vertex is next
  // to the face points of its n-gons (n) and a face point to the n-gon's irregular corners.
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (!irregular[v]) continue;
    FanCost fan{m.valence(v), m.vertex_face_count(v), 2, 0};
    if (x && m.valence(v) > kSharedPieceValence) {
      std::vector<int> star;
      for (int i = 0; i < m.vertex_face_count(v); ++i) star.push_back(m.corner_face(m.vertex_corners(v)[i]));
      fan.curved = !flat_faces(m, *x, with_ring(m, star));
    }
    if (quads) {
      fan.nearby = nearby_valence(m, v, irregular_valence);
    } else {
      for (int i = 0; i < m.vertex_face_count(v); ++i) {
        const int f = m.corner_face(m.vertex_corners(v)[i]);
        if (!in_cap[f] && m.face_size(f) != 4) fan.nearby += m.face_size(f);
      }
    }
    c.fans.push_back(fan);
  }
  for (int f = 0; f < m.num_faces(); ++f) {
    const int n = m.face_size(f);
    if (n != 4 && !in_cap[f]) {  // the face point: a level-1 vertex of valence n
      FanCost fan{n, n, 2, 0};
      if (x && n > kSharedPieceValence) fan.curved = !flat_faces(m, *x, with_ring(m, {f}));
      for (int h = m.face_begin(f); h < m.face_end(f); ++h)
        if (irregular[m.corner_vertex(h)]) fan.nearby += m.valence(m.corner_vertex(h));
      c.fans.push_back(fan);
    }
    if (n == 4) {
      // All quads: the quad is irregular when a corner is. At level 1 each of its 4 children
      // has one cage corner: one irregular child per irregular corner.
      int at = 0;
      for (int h = m.face_begin(f); h < m.face_end(f); ++h) at += irregular[m.corner_vertex(h)];
      c.irregular_quads += quads ? (at > 0 ? 1 : 0) : at;
    } else if (!in_cap[f]) {
      c.irregular_quads += n;  // each child quad has the face point at a corner
    }
  }
  // Semi-sharp edges: the builder refines the quads beside one until its sharpness decays (at
  // most ceil(s) + 1 levels), a row of pieces along it per level on each side, and their
  // patches get the knots of those rows.
  for (int e = 0; e < m.num_edges(); ++e) {
    const float s = base.edge_sharpness[e];
    if (!(s > 0 && s < kInfiniteSharpness)) continue;
    const int levels = std::min(static_cast<int>(std::ceil(s)) + 1, 12);
    const double along = std::pow(2.0, levels);
    c.semi_pieces += 3.0 * along;  // measured: 2.7 .. 3.1 x along on the corpus
    c.semi_poles += 0.5 * along;   // most of those knots are removed again (one polynomial)
  }
  return c;
}

ResourceEstimate estimate(const CageCost& c, const std::vector<FanCost>& fans, const EstimateOptions& o) {
  ResourceEstimate e;
  const double regular = std::max(0.0, c.quads - c.irregular_quads);
  e.patches = c.quads;
  e.faces = c.quads + c.semi_pieces;
  e.poles = 16.0 * c.quads + c.semi_poles + c.cap_poles;
  const double irregular_faces = c.irregular_quads + c.caps;
  if (o.packed) {
    // Regular regions pack into rectangles of about one pole per quad; the quads at irregular
    // vertices stay a face each, and the regions between them make about 1 face in 8 more.
    const double packs = 0.125 * irregular_faces + (regular > 0 ? 1 : 0);
    e.exported_faces = irregular_faces + packs;
    e.exported_poles = regular + 16.0 * (packs + c.irregular_quads) + c.semi_poles + c.cap_poles;
  } else {
    e.exported_faces = c.quads + c.caps;
    e.exported_poles = e.poles;
  }
  e.bytes = kProcessBytes + kBytesPerQuad * c.quads + kBytesPerPiece * c.semi_pieces +
            kBytesPerPatchPole * (c.semi_poles + c.cap_poles);
  if (o.build_brep)
    e.bytes += kBytesPerFace * e.exported_faces + kBytesPerEdge * 2.2 * e.exported_faces +
               kBytesPerFacePole * e.exported_poles;
  else
    e.bytes += kBytesPerFacePoleNoBrep * e.exported_poles;
  e.seconds = kStartSeconds + kSecondsPerPiece * e.faces + kSecondsPerPole * e.exported_poles +
              (o.build_brep ? kSecondsPerFace * e.exported_faces : 0.0);
  e.seconds += kSecondsPerCapValence2 * c.cap_valence2;
  std::set<int> valences;
  for (const FanCost& f : fans) {
    e = e + fan_estimate(f, o);
    valences.insert(f.valence);
  }
  // The quality stage's exact limit: Stam's eigenbasis per valence, a few (2n+8)^2 matrices,
  // and their O(n^3) eigen-decomposition; and samples on every patch.
  if (o.quality) {
    for (int n : valences) {
      const double k = 2.0 * n + 8;
      e.bytes += 5 * 8.0 * k * k;
      e.seconds += 2e-9 * k * k * k;
    }
    e.seconds += 2e-5 * 81 * e.patches;
  }
  return e;
}

}  // namespace

ResourceEstimate operator+(const ResourceEstimate& a, const ResourceEstimate& b) {
  ResourceEstimate e;
  e.faces = a.faces + b.faces;
  e.patches = a.patches + b.patches;
  e.poles = a.poles + b.poles;
  e.exported_faces = a.exported_faces + b.exported_faces;
  e.exported_poles = a.exported_poles + b.exported_poles;
  e.bytes = a.bytes + b.bytes;
  e.seconds = a.seconds + b.seconds;
  return e;
}

ResourceEstimate operator-(const ResourceEstimate& a, const ResourceEstimate& b) {
  ResourceEstimate e;
  e.faces = a.faces - b.faces;
  e.patches = a.patches - b.patches;
  e.poles = a.poles - b.poles;
  e.exported_faces = a.exported_faces - b.exported_faces;
  e.exported_poles = a.exported_poles - b.exported_poles;
  e.bytes = a.bytes - b.bytes;
  e.seconds = a.seconds - b.seconds;
  return e;
}

int nearby_valence(const PolyMesh& m, int v, const std::vector<int>& valence_of) {
  std::vector<int> near;
  for (int i = 0; i < m.vertex_face_count(v); ++i) {
    const int f = m.corner_face(m.vertex_corners(v)[i]);
    for (int g = m.face_begin(f); g < m.face_end(f); ++g)
      if (m.corner_vertex(g) != v && valence_of[m.corner_vertex(g)] > 0) near.push_back(m.corner_vertex(g));
  }
  std::sort(near.begin(), near.end());
  near.erase(std::unique(near.begin(), near.end()), near.end());
  int sum = 0;
  for (int w : near) sum += valence_of[w];
  return sum;
}

ResourceEstimate fan_estimate(const FanCost& f, const EstimateOptions& o) {
  // Per quad at the vertex: 3 pieces per level down to the zone and the zone's 4 and 1, a patch
  // whose knots halve towards the corner, (levels + 7)^2 poles instead of 16.
  const double L = std::max(f.levels, 1);
  const double pieces = f.corners * (3.0 * L + 2);
  const double poles = f.corners * ((L + 7) * (L + 7) - 16);
  ResourceEstimate e;
  e.faces = pieces;
  e.poles = poles;
  e.exported_poles = poles;
  // The piece: the fan's own star and the stars next to it; held twice during a rebuild.
  const double piece = kBytesPerFanValence * f.valence + kBytesPerNearbyValence * f.nearby;
  e.bytes = kBytesPerPiece * pieces + kBytesPerPatchPole * poles + piece * (o.rebuilt ? 2 : 1) +
            (o.build_brep ? kBytesPerFacePole : kBytesPerFacePoleNoBrep) * poles;
  e.seconds = kSecondsPerPiece * pieces + kSecondsPerPole * poles + kSecondsPerFanValenceLevel * f.valence * L +
              (f.corners > kSharedPieceValence ? 0.0 : kSecondsPerFanValence2Level * f.valence * f.corners * L) +
              kSecondsPerFanValence2Intersections * f.valence * f.corners +
              kSecondsPerNearbyValence * f.nearby * (o.rebuilt ? 2 : 1);
  return e;
}

ResourceEstimate estimate_conversion(const SubdivLevel& base, int extra_levels, const EstimateOptions& options) {
  const bool predict = options.tolerance > 0 && options.positions &&
                       options.positions->size() == static_cast<size_t>(base.mesh.num_vertices());
  const CageCost c = cage_cost(base, options.polar, predict ? options.positions : nullptr);
  std::vector<FanCost> fans = c.fans;
  for (FanCost& f : fans) {
    f.levels = 2 + std::max(0, extra_levels);
    if (predict && f.curved && f.valence > kSharedPieceValence) {
      // The levels that take kPredictedDeviation down to the tolerance at this valence's rate.
      const double need = std::log(kPredictedDeviation / options.tolerance) / std::log(deviation_rate(f.valence));
      if (need > 0) f.levels = std::max(f.levels, 2 + std::min(static_cast<int>(std::ceil(need)), kMaxFanExtraLevels));
    }
  }
  return estimate(c, fans, options);
}

ResourceEstimate estimate_conversion(const SubdivLevel& base, int extra_levels, bool build_brep) {
  EstimateOptions o;
  o.build_brep = build_brep;
  return estimate_conversion(base, extra_levels, o);
}

ResourceEstimate estimate_conversion(const SubdivLevel& base, const std::vector<FanCost>& fans,
                                     const EstimateOptions& options) {
  return estimate(cage_cost(base, options.polar, nullptr), fans, options);
}

ResourceEstimate estimate_refinement(const SubdivLevel& base, int levels) {
  const PolyMesh& m = base.mesh;
  ResourceEstimate e;
  e.faces = levels <= 0 ? m.num_faces() : m.num_corners() * std::pow(4.0, levels - 1);
  e.bytes = e.faces * kRefineBytesPerFace;
  return e;
}

void validate(const ResourceLimits& limits) {
  for (const auto& [setting, value] : {std::pair{"max_faces", limits.max_faces}, std::pair{"max_memory", limits.max_memory}})
    if (value && !(*value > 0 && std::isfinite(*value))) throw SettingsError(setting, "must be a positive number");
  if (limits.threads && (*limits.threads < 1 || *limits.threads > kMaxThreads))
    throw SettingsError("threads", "must be 1 .. " + std::to_string(kMaxThreads));
}

void check_refine_levels(int levels) {
  if (levels < 0 || levels > kMaxRefineLevels)
    throw SettingsError("levels", "must be 0 .. " + std::to_string(kMaxRefineLevels));
}

double memory_size(const std::string& text) {
  double bytes = 0;
  if (!parse_memory_size(text, bytes))
    throw SettingsError("max_memory", "'" + printable(text, 40) + "' is not a size (bytes, or a number with K, M, G or T, e.g. 8G)");
  return bytes;
}

void check_resources(const ResourceEstimate& estimate, const ResourceLimits& limits, double default_max_faces,
                     const std::string& what, const std::string& advice) {
  const double max_faces = limits.max_faces.value_or(default_max_faces);
  const double max_memory = limits.max_memory ? *limits.max_memory : default_max_memory();
  if (estimate.faces > max_faces)
    throw ResourceError(what + " would make about " + short_number(estimate.faces) + " faces (limit " +
                        short_number(max_faces) + (limits.max_faces ? "" : ", the default") + "); " + advice +
                        ", or raise the limit with --max-faces N (Python: max_faces=N)");
  if (estimate.bytes > max_memory)
    throw ResourceError(what + " would need about " + bytes_text(estimate.bytes) + " of memory (limit " +
                        bytes_text(max_memory) +
                        (limits.max_memory ? "" : ", 3/4 of the memory available to this process") + "); " +
                        advice + ", or raise the limit with --max-memory SIZE (Python: max_memory=bytes)");
}

}  // namespace subd2nurbs::pipeline
