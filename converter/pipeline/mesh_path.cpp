#include "converter/pipeline/mesh_path.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "converter/pipeline/settings_error.h"
#include "converter/pipeline/text.h"
#include "core/fit/planar_regions.h"
#include "core/limit/limit_evaluator.h"
#include "core/mesh/quad_recovery.h"
#include "core/util/error.h"
#include "core/util/vec3.h"
#include "io/cage_reader.h"
#include "io/input_file.h"
#include "io/target_reader.h"

namespace subd2nurbs::pipeline {

namespace {

using vec3::sub;
using vec3::dot;
using vec3::cross;
using vec3::norm;

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }


/// Angle between two vectors, degrees (0 for a zero vector).
double angle_deg(const Point3& a, const Point3& b) {
  const double na = norm(a), nb = norm(b);
  if (!(na > 0 && nb > 0)) return 0;
  return std::acos(std::clamp(dot(a, b) / (na * nb), -1.0, 1.0)) * 180.0 / M_PI;
}

bool all_triangles(const MeshInput& m) {
  return std::all_of(m.face_sizes.begin(), m.face_sizes.end(), [](int n) { return n == 3; });
}

/// The road by rules 2 .. 5 (the header's comment); `recovery`: the quad recovery of the
/// file's triangles when already made (else made here when needed).
InputRoute route(const LoadedCage& read, const std::string& path, InputKind requested,
                 const QuadRecoveryResult* recovery) {
  if (requested == InputKind::Mesh) return {true, "the input was declared a mesh"};
  if (requested == InputKind::Cage) return {false, "the input was declared a cage"};
  const MeshInput& in = read.input;
  const bool file_triangles = read.recovery.applied || all_triangles(in);
  if (!file_triangles) {
    const long others = std::count_if(in.face_sizes.begin(), in.face_sizes.end(), [](int n) { return n != 3; });
    return {false, "it has " + std::to_string(others) + " faces that are not triangles: a cage"};
  }
  if (!in.creases.empty() || !in.corners.empty() || !in.holes.empty())
    return {false, "it has crease, corner or hole tags: a cage"};
  int triangles = 0, unpaired = 0;
  if (read.recovery.applied) {
    triangles = read.recovery.source_triangles;
    unpaired = read.recovery.triangles_kept - read.recovery.fan_triangles;
  } else {
    QuadRecoveryResult made;
    const QuadRecoveryResult& r = recovery ? *recovery : (made = recover_quads(in));
    triangles = r.input_triangles;
    unpaired = r.triangles_kept - r.fan_triangles;
  }
  if (unpaired == 0)
    return {false, "its " + std::to_string(triangles) + " triangles pair back into quads: a triangulated cage"};
  const std::string why = "its " + std::to_string(triangles) + " triangles do not pair back into quads (" +
                          std::to_string(unpaired) + " stay triangles)";
  const CageFormat format = cage_format(path);
  const bool mesh_file = is_mesh_format(format) || format == CageFormat::Gltf;
  if (!mesh_file && triangles < kMinMeshTriangles)
    return {false, why + ", but fewer than " + std::to_string(kMinMeshTriangles) +
                       " triangles outside an STL, PLY, OFF or glTF file are taken as a triangle cage"};
  return {true, why + ": a mesh to reproduce"};
}

/// The file's faces as triangles (polygons fan-triangulated), without tags.
void triangulate(MeshInput& m) {
  if (all_triangles(m)) return;
  std::vector<int> sizes, indices;
  for (const auto& t : fan_triangles(m.face_sizes, m.face_indices)) {
    sizes.push_back(3);
    indices.insert(indices.end(), t.begin(), t.end());
  }
  m.face_sizes = std::move(sizes);
  m.face_indices = std::move(indices);
}

/// The triangles' two-sided features: per input feature edge (not on the boundary) its end
/// points and its dihedral angle (between the two triangles' normals), degrees.
struct MeshFeatureEdge {
  Point3 a, b;
  double angle = 0;
};

std::vector<MeshFeatureEdge> mesh_feature_edges(const MeshInput& mesh, const PolyMesh& poly, const FeatureSet& features) {
  std::vector<MeshFeatureEdge> out;
  auto face_normal = [&](int f) {
    const int* v = poly.face_vertices(f);
    const auto& p = mesh.positions;
    return cross(sub(p[v[1]], p[v[0]]), sub(p[v[2]], p[v[0]]));
  };
  for (const auto& e : features.edges) {
    const int id = poly.find_edge(e[0], e[1]);
    if (id < 0 || poly.is_boundary_edge(id)) continue;
    const int h = poly.edge_corner(id);
    out.push_back({mesh.positions[e[0]], mesh.positions[e[1]],
                   angle_deg(face_normal(poly.corner_face(h)), face_normal(poly.corner_face(poly.twin(h))))});
  }
  return out;
}

double segment_distance2(const Point3& p, const Point3& a, const Point3& b) {
  const Point3 ab = sub(b, a);
  const double len2 = dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(dot(sub(p, a), ab) / len2, 0.0, 1.0) : 0.0;
  const Point3 q{a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]};
  const Point3 d = sub(p, q);
  return dot(d, d);
}

/// The mesh's feature edges in a uniform grid (hashed cells of about two mean edge lengths), for
/// the nearest edge to a point among those that pass a filter: the cells are searched ring by
/// ring around the point's cell until no closer edge can remain.
class FeatureEdgeGrid {
 public:
  explicit FeatureEdgeGrid(const std::vector<MeshFeatureEdge>& edges) : edges_(edges) {
    if (edges.empty()) return;
    double total = 0;
    for (int k = 0; k < 3; ++k) lo_[k] = INFINITY, hi_[k] = -INFINITY;
    for (const MeshFeatureEdge& e : edges) {
      total += norm(sub(e.b, e.a));
      for (int k = 0; k < 3; ++k)
        lo_[k] = std::min({lo_[k], e.a[k], e.b[k]}), hi_[k] = std::max({hi_[k], e.a[k], e.b[k]});
    }
    const double extent = std::max({hi_[0] - lo_[0], hi_[1] - lo_[1], hi_[2] - lo_[2]});
    cell_ = std::max(2 * total / static_cast<double>(edges.size()), extent / 256);
    if (!(cell_ > 0)) cell_ = 1;
    for (int i = 0; i < static_cast<int>(edges.size()); ++i) {
      const Cell a = cell_of(edges[i].a), b = cell_of(edges[i].b);
      for (int x = std::min(a[0], b[0]); x <= std::max(a[0], b[0]); ++x)
        for (int y = std::min(a[1], b[1]); y <= std::max(a[1], b[1]); ++y)
          for (int z = std::min(a[2], b[2]); z <= std::max(a[2], b[2]); ++z) cells_[key({x, y, z})].push_back(i);
    }
    const Cell top = cell_of(hi_);
    max_ring_ = std::max({top[0], top[1], top[2]}) + 1;
  }

  /// The index of the nearest edge to p that `accept` takes (-1 if none), its squared distance in d2.
  template <class Accept>
  int nearest(const Point3& p, Accept&& accept, double& d2) const {
    d2 = INFINITY;
    if (edges_.empty()) return -1;
    Cell c = cell_of(p);
    // p outside the grid's box: start the rings at the nearest cell inside it
    for (int k = 0; k < 3; ++k) c[k] = std::clamp(c[k], 0, max_ring_);
    int best = -1;
    for (int ring = 0; ring <= max_ring_ + 1; ++ring) {
      for (int x = c[0] - ring; x <= c[0] + ring; ++x)
        for (int y = c[1] - ring; y <= c[1] + ring; ++y)
          for (int z = c[2] - ring; z <= c[2] + ring; ++z) {
            if (std::max({std::abs(x - c[0]), std::abs(y - c[1]), std::abs(z - c[2])}) != ring) continue;
            const auto it = cells_.find(key({x, y, z}));
            if (it == cells_.end()) continue;
            for (int i : it->second) {
              const MeshFeatureEdge& e = edges_[static_cast<std::size_t>(i)];
              if (!accept(e)) continue;
              const double d = segment_distance2(p, e.a, e.b);
              if (d < d2 || (d == d2 && i < best)) d2 = d, best = i;
            }
          }
      // every point of a cell at ring r + 1 is at least r cells away from p's projection onto the
      // grid's box (in the start cell), hence from p (the projection onto a box shortens distances)
      const double reach = ring * cell_;
      if (best >= 0 && d2 <= reach * reach) break;
    }
    return best;
  }

 private:
  using Cell = std::array<int, 3>;
  Cell cell_of(const Point3& p) const {
    Cell c;
    for (int k = 0; k < 3; ++k) c[k] = static_cast<int>(std::floor(std::clamp(p[k] - lo_[k], 0.0, hi_[k] - lo_[k]) / cell_));
    return c;
  }
  static std::uint64_t key(const Cell& c) {
    return (std::uint64_t(std::uint32_t(c[0]) & 0x1fffff) << 42) | (std::uint64_t(std::uint32_t(c[1]) & 0x1fffff) << 21) |
           (std::uint64_t(std::uint32_t(c[2]) & 0x1fffff));
  }
  const std::vector<MeshFeatureEdge>& edges_;
  Point3 lo_{}, hi_{};
  double cell_ = 1;
  int max_ring_ = 0;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

/// (u, v) of the point at fraction t along edge `corner` (0..3) of a quad's ptex face.
std::pair<double, double> quad_edge_uv(int corner, double t) {
  switch (corner) {
    case 0: return {t, 0};
    case 1: return {1, t};
    case 2: return {1 - t, 1};
    default: return {0, 1 - t};
  }
}

/// The normal angle across each infinitely sharp interior edge of the fitted cage (evaluated on
/// both sides at 1/4, 1/2, 3/4 of the edge), against the mesh's dihedral at the closest feature
/// edge of the mesh.
FeatureAngleStats measure_feature_angles(const SubdivLevel& cage, const std::vector<Point3>& positions,
                                         const std::vector<MeshFeatureEdge>& mesh_edges,
                                         const std::vector<std::array<int, 2>>& sector_edges) {
  FeatureAngleStats s;
  if (mesh_edges.empty()) return s;
  const PolyMesh& m = cage.mesh;
  std::vector<char> sector(static_cast<std::size_t>(m.num_edges()), 0);  // no mesh feature: not measured
  for (const auto& [a, b] : sector_edges)
    if (const int e = m.find_edge(a, b); e >= 0) sector[static_cast<std::size_t>(e)] = 1;
  const LimitEvaluator limit(cage, positions);
  const FeatureEdgeGrid grid(mesh_edges);
  double sum = 0;
  for (int e = 0; e < m.num_edges(); ++e) {
    if (m.is_boundary_edge(e) || cage.edge_sharpness[e] < kInfiniteSharpness || sector[static_cast<std::size_t>(e)])
      continue;
    const int h = m.edge_corner(e), g = m.twin(h);
    const int fh = m.corner_face(h), fg = m.corner_face(g);
    if (m.face_size(fh) != 4 || m.face_size(fg) != 4) continue;
    for (const double t : {0.25, 0.5, 0.75}) {
      const auto [uh, vh] = quad_edge_uv(h - m.face_begin(fh), t);
      const auto [ug, vg] = quad_edge_uv(g - m.face_begin(fg), 1 - t);
      LimitSample a, b;
      try {
        a = limit.evaluate_ptex(limit.first_ptex(fh), uh, vh);
        b = limit.evaluate_ptex(limit.first_ptex(fg), ug, vg);
      } catch (const std::exception&) {
        continue;  // no limit there (a hole's side)
      }
      const double surface = angle_deg(a.normal, b.normal);
      // The closest mesh feature edge running along the curve (within 30 degrees of its
      // direction: near a corner the closest edge may belong to another curve).
      const Point3 along = cross(a.normal, b.normal);
      double best = INFINITY;
      const int nearest = grid.nearest(
          a.p,
          [&](const MeshFeatureEdge& me) {
            const Point3 dir = sub(me.b, me.a);
            return !(norm(along) > 0.1 && norm(dir) > 0 &&
                     std::abs(dot(along, dir)) < 0.866 * norm(along) * norm(dir));
          },
          best);
      if (nearest < 0) continue;
      const double mesh_angle = mesh_edges[static_cast<std::size_t>(nearest)].angle;
      const double diff = std::abs(surface - mesh_angle);
      sum += diff;
      ++s.samples;
      if (diff > s.max_difference) s.max_difference = diff, s.where_edge = e, s.where = a.p;
    }
  }
  if (s.samples > 0) s.mean_difference = sum / s.samples;
  return s;
}

/// The planar regions of the target's triangles, however narrow and down to 1e-4 of the mesh's
/// area (the cage's faces and vertices held in them: planar_constraints per cage). No width
/// limit: a face is held only when its whole limit support lies on the plane, so a strip narrower
/// than a cage edge holds faces only between two infinitely sharp creases (a wall one quad high,
/// whose faces' limit depends on the crease vertices alone); a faceted cylinder's strips, bounded
/// by soft edges, hold none. The area limit (1e-3 by default) lowered for the same reason: small
/// walls (a boss 0.27 wide and 0.2 high on featuretype, 0.9e-3 of its area) are flat faces too.
std::vector<PlanarRegion> planar_regions(const ShapeTarget& target) {
  PlanarRegionOptions po;
  po.min_area = 1e-4;
  return detect_planar_regions(target.points(), target.triangles(), po);
}

/// What one round of the size rule shares with the others: the mesh, its target and planar
/// regions, the progress.
struct RoundInput {
  const MeshInput& tri;
  const std::string& path;
  const ShapeTarget& target;
  const std::vector<PlanarRegion>& regions;
  const MeshPathProgress& progress;
};

/// One remesh of the mesh at `ro`'s size and the fit of that cage to it: the cage, its fitted
/// positions and the report's remesh, feature, fit and planar members (`features`: the mesh's
/// features as the remesher found them, for the feature angles).
/// \throw Error (remesh or fit impossible; kind Usage "cancelled")
MeshCage remesh_and_fit(const RoundInput& in, const QuadRemeshOptions& ro, const std::string& round_text,
                        FeatureSet& features) {
  MeshCage out;
  MeshPathReport& rep = out.report;
  rep.target_faces = ro.target_faces;
  rep.edge_length = ro.edge_length;
  auto t = Clock::now();
  if (in.progress.stage)
    in.progress.stage("remeshing " + std::to_string(in.tri.num_faces()) + " triangles into a quad cage" + round_text);
  QuadRemeshResult rr = quad_remesh(in.tri, ro, in.progress.fraction);
  if (rr.cancelled) throw Error(ErrorKind::Usage, "cancelled");
  rep.remesh_ms = ms_since(t);
  rep.remesh = rr.stats;
  out.sector_edges = std::move(rr.sector_edges);
  rep.feature_edges_in = static_cast<int>(rr.features.edges.size());
  rep.corners_in = static_cast<int>(rr.features.corners.size() - rr.features.darts.size());
  rep.faded_edges_in = rr.features.faded_edges;
  rep.fading_ends_in = static_cast<int>(rr.features.darts.size());
  rep.plane_edges_in = rr.features.plane_edges;
  rep.feature_chains_in = rr.features.chains;
  features = std::move(rr.features);

  // The cage, validated as a file's cage would be (a remesher fault is an error, not a crash).
  LoadedCage cage;
  cage.path = in.path;
  cage.input = std::move(rr.cage);
  out.cage.cage = std::move(cage);
  Diagnostics validation;
  out.cage.level = SubdivLevel::from_validated(validate_cage(out.cage.cage, &validation), out.cage.cage.input);
  const std::vector<Point3> start = out.cage.positions();

  // The fit of the cage's limit surface to the mesh.
  if (in.progress.stage)
    in.progress.stage("fitting the cage's " + std::to_string(out.cage.cage.input.num_faces()) + " quads to the mesh" +
                      round_text);
  // Samples of level 2 (16 per quad): the cage's quads are a few mesh triangles wide, so 16
  // samples per quad still outnumber the mesh's vertices; 4 x cheaper than level 3.
  rep.fit_options.levels = 2;
  // Until the two-sided distance gains less than 2 % in an iteration (the fit's min_gain, as
  // `subd2nurbs fit`), 40 iterations at most: the CAD meshes stop after 7 .. 15, where their
  // cages, not the fit, limit the distance; a smooth scan goes on (bob's limit scan: 27, half
  // the distance to the true limit of 10; docs/meshes.md "Measured against bob's true limit").
  rep.fit_options.max_iterations = 40;
  rep.fit_options.min_gain = 0.02;
  // The crease curves' sides held at the mesh's normals where a quad meets a crease at an acute
  // angle (core/fit/shape_fit.h crease_normal_weight; docs/meshes.md, fandisk's fan tip).
  rep.fit_options.crease_normal_weight = 1;
  // The cage's vertices that planar regions' faces depend on, held on their planes (core/fit/planar_regions.h).
  const PlanarConstraints planar = planar_constraints(out.cage.level, start, in.target.points(),
                                                      in.target.triangles(), in.regions, in.target.diagonal());
  rep.fit_options.vertex_planes = vertex_planes(planar, in.regions);
  ShapeFitProgress fit_progress;
  if (in.progress.fraction)
    // The fit stops when it stops gaining, after 7 .. 27 of its 40 iterations on the meshes
    // measured: the fraction rises as 1 - exp(-iterations / 8) (0.6 at 7, 0.97 at 27), not
    // linearly to a cap it seldom reaches.
    fit_progress = [&](int iteration, double) {
      return in.progress.fraction(1.0 - std::exp(-(iteration + 1.0) / 8.0));
    };
  // The planar regions' faces made exactly planar (the held vertices onto their planes) before
  // the fitted cage is measured.
  const ShapeFitAdjust flatten = [&](std::vector<Point3>& positions) {
    rep.planar = flatten_planar_regions(out.cage.level, planar, positions, in.regions, in.target.diagonal());
  };
  rep.fit = run_shape_fit(out.cage.level, start, in.target, rep.fit_options, fit_progress, flatten);
  if (rep.fit.fit.stop == ShapeFitStop::Cancelled) throw Error(ErrorKind::Usage, "cancelled");
  out.positions = rep.fit.fit.positions;
  rep.fit_ms = rep.fit.fit_ms;
  rep.measure_ms = rep.fit.measure_ms;
  return out;
}

MeshPathRound round_of(const MeshPathReport& r) {
  MeshPathRound round;
  round.target_faces = r.target_faces;
  round.quads = r.remesh.faces;
  round.to_mesh = r.fit.after.limit_to_target.max;
  round.from_mesh = r.fit.after.target_to_limit.max;
  round.ms = r.remesh_ms + r.fit_ms + r.measure_ms;
  round.remesh_ms = r.remesh_ms;
  return round;
}

/// The size rule's next target (mesh_path.h): d x quads is about a constant; its geometric mean
/// over the rounds so far, over kSizeMargin x the tolerance, at least the first round's target
/// over kMaxSizeFactor (the caller checks the upper limit).
int next_target_faces(const std::vector<MeshPathRound>& rounds, double tolerance) {
  double log_c = 0;
  int n = 0;
  for (const MeshPathRound& r : rounds)
    if (r.quads > 0 && r.distance() > 0) log_c += std::log(r.distance() * r.quads), ++n;
  const double first = rounds.front().target_faces;
  if (n == 0) return static_cast<int>(first);
  const double quads = std::exp(log_c / n) / (kSizeMargin * tolerance);
  return static_cast<int>(std::lround(std::clamp(quads, first / kMaxSizeFactor, 1e9)));
}

/// Whether round `a` is to be kept over `b` (the size rule: the fewest quads meeting the
/// tolerance, else the closest).
bool better_round(const MeshPathRound& a, const MeshPathRound& b, double tolerance) {
  const bool a_meets = a.distance() <= tolerance, b_meets = b.distance() <= tolerance;
  if (a_meets != b_meets) return a_meets;
  return a_meets ? a.quads < b.quads : a.distance() < b.distance();
}

void write_stats(JsonWriter& w, const QuadRemeshStats& r) {
  w.begin_object();
  w.members("faces", r.faces, "vertices", r.vertices, "extraordinary_vertices", r.extraordinary_vertices,
            "feature_edges", r.feature_edges, "feature_chains_kept", r.feature_chains_kept, "corners", r.corners);
  w.members("coarse_quads", r.coarse_quads, "coarse_triangles", r.coarse_triangles, "flips", r.flips, "attempts", r.attempts,
            "spacing", r.spacing);
  w.members("cleanup_rotations", r.cleanup_rotations, "cleanup_merges", r.cleanup_merges, "relocations", r.relocations,
            "concave_sectors", r.concave_sectors, "sliver_flips", r.sliver_flips, "cap_flips", r.cap_flips, "tight_loops", r.tight_loops);
  w.members("field_singularities", r.field_singularities, "position_dislocations", r.position_dislocations,
            "position_dislocations_left", r.position_dislocations_left, "field_threads", r.field_threads);
  w.members("euler_characteristic", r.euler_cage, "boundaries", r.boundaries_cage, "components", r.components_cage);
  w.end_object();
}

}  // namespace

const char* to_string(InputKind kind) {
  switch (kind) {
    case InputKind::Auto: return "auto";
    case InputKind::Mesh: return "mesh";
    case InputKind::Cage: return "cage";
  }
  return "?";
}

InputKind input_kind(const std::string& name) {
  for (InputKind k : {InputKind::Auto, InputKind::Mesh, InputKind::Cage})
    if (name == to_string(k)) return k;
  throw SettingsError("input", "must be auto, mesh or cage, not '" + printable(name) + "'");
}

void validate(const MeshPathSettings& s) {
  if (s.target_faces < 0) throw SettingsError("target_faces", "must be >= 0 (0: automatic)");
  if (!(s.edge_length >= 0 && std::isfinite(s.edge_length)))
    throw SettingsError("edge_length", "must be a number >= 0 (0: automatic)");
  if (!(s.fit_tolerance >= 0 && s.fit_tolerance < 1))
    throw SettingsError("fit_tolerance", "must be a number from 0 (off) to below 1 (of the diagonal)");
  if (!(s.feature_angle > 0 && s.feature_angle < 180))
    throw SettingsError("feature_angle", "must be between 0 and 180 degrees");
}

int automatic_target_faces(const MeshInput& mesh) {
  // Quads for the mesh's area at an edge length of 1/25 of the bounding-box diagonal, within
  // 100 .. 1500: a closed box of side a (diagonal a sqrt 3) gets 6 a^2 / (a sqrt 3 / 25)^2 = 1250.
  Point3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  std::vector<char> used(mesh.positions.size(), 0);
  for (int v : mesh.face_indices) used[static_cast<std::size_t>(v)] = 1;
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    if (used[i])
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], mesh.positions[i][k]), hi[k] = std::max(hi[k], mesh.positions[i][k]);
  const double diag = norm(sub(hi, lo));
  double area = 0;
  int off = 0;
  for (int n : mesh.face_sizes) {
    const Point3& a = mesh.positions[mesh.face_indices[off]];
    for (int i = 1; i + 1 < n; ++i)
      area += 0.5 * norm(cross(sub(mesh.positions[mesh.face_indices[off + i]], a),
                               sub(mesh.positions[mesh.face_indices[off + i + 1]], a)));
    off += n;
  }
  if (!(diag > 0)) return 100;
  const double h = diag / 25;
  return static_cast<int>(std::clamp(area / (h * h), 100.0, 1500.0));
}

InputRoute route_input(const LoadedCage& read, const std::string& path, InputKind requested) {
  return route(read, path, requested, nullptr);
}

LoadedSource load_source(const std::string& path, InputKind requested, const UsdReadOptions& usd) {
  LoadedSource s;
  if (!is_mesh_format(cage_format(path))) {
    LoadedCage read = read_cage(path, {}, usd);
    s.route = route_input(read, path, requested);
    if (s.route.mesh) {
      s.mesh = std::move(read);  // OBJ as read; glTF: its recovered quads triangulated again
    } else {
      s.cage = load_input(std::move(read));
      return s;
    }
  } else {
    // STL, PLY, OFF: read once without quad recovery (the mesh road wants the triangles); the
    // recovery is made here, and applied only on the cage road, as read_cage would have.
    MeshReadOptions raw;
    raw.recover_quads = false;
    LoadedCage read = read_cage(path, raw, usd);
    std::optional<QuadRecoveryResult> recovery;
    if (requested != InputKind::Mesh && read.repair.triangles_only) recovery = recover_quads(read.input);
    s.route = route(read, path, requested, recovery ? &*recovery : nullptr);
    if (!s.route.mesh) {
      if (recovery) {
        std::vector<int> face_line;
        for (const std::vector<int>& sources : recovery->sources)
          face_line.push_back(read.face_line[static_cast<std::size_t>(sources[0])]);
        read.face_line = std::move(face_line);
        take_recovered_quads(read, std::move(*recovery));
      }
      s.cage = load_input(std::move(read));
      return s;
    }
    s.mesh = std::move(read);
  }
  for (const Diagnostic& d : s.mesh.diagnostics) s.warnings.push_back(format_diagnostic(s.mesh, d));
  return s;
}

MeshCage mesh_to_cage(const LoadedCage& mesh, const MeshPathSettings& settings, const MeshPathProgress& progress) {
  validate(settings);
  MeshInput tri = mesh.input;  // the shape: triangles; infinitely sharp creases are the user's features
  triangulate(tri);
  tri.creases.erase(std::remove_if(tri.creases.begin(), tri.creases.end(),
                                   [](const CreaseTag& c) { return c.sharpness < kInfiniteSharpness; }),
                    tri.creases.end());
  tri.corners.clear();
  tri.holes.clear();

  QuadRemeshOptions ro;
  ro.features.angle_degrees = settings.feature_angle;
  std::string size_rule = "given";
  if (settings.target_faces > 0) {
    ro.target_faces = settings.target_faces;
    ro.aim_at_target = settings.aim_at_target;
  } else if (settings.edge_length > 0) {
    ro.edge_length = settings.edge_length;
    ro.exact_spacing = settings.exact_spacing;
  } else {
    ro.target_faces = automatic_target_faces(tri);
    size_rule = settings.fit_tolerance > 0 ? "fit_tolerance" : "automatic";
  }
  const double tolerance = size_rule == "fit_tolerance" ? settings.fit_tolerance : 0.0;

  TargetShape shape;
  shape.points = tri.positions;
  shape.triangles = fan_triangles(tri.face_sizes, tri.face_indices);
  const ShapeTarget target = make_target(std::move(shape), mesh.path);
  const std::vector<PlanarRegion> regions = planar_regions(target);
  const RoundInput in{tri, mesh.path, target, regions, progress};

  // The first round at the automatic (or given) size; then, with a tolerance, the size rule
  // (mesh_path.h): finer while the distance misses the tolerance, or once coarser when far below.
  FeatureSet features;
  MeshCage out = remesh_and_fit(in, ro, "", features);
  std::vector<MeshPathRound> rounds{round_of(out.report)};
  double remesh_ms = out.report.remesh_ms, fit_ms = out.report.fit_ms, measure_ms = out.report.measure_ms;
  int kept = 0, predicted = 0;
  while (tolerance > 0 && static_cast<int>(rounds.size()) < kMaxSizeRounds) {
    const MeshPathRound& last = rounds.back();
    const bool coarser = rounds.size() == 1 && last.distance() < kCoarsenBelow * tolerance;
    if (!(last.distance() > tolerance || coarser) || !last.failure.empty()) break;
    const int next = next_target_faces(rounds, tolerance);
    if (next > kMaxSizeFactor * rounds.front().target_faces) {
      predicted = next;  // beyond the size limit: not tried
      break;
    }
    if (std::any_of(rounds.begin(), rounds.end(), [&](const MeshPathRound& r) { return r.target_faces == next; }))
      break;  // at the lower limit: that size was tried
    ro.target_faces = next;
    const std::string round_text = " (round " + std::to_string(rounds.size() + 1) + ": " +
                                   short_number(last.distance()) + " of the diagonal " +
                                   (coarser ? "is far within" : "misses") + " the fit tolerance " +
                                   short_number(tolerance) + ")";
    FeatureSet round_features;
    try {
      MeshCage made = remesh_and_fit(in, ro, round_text, round_features);
      rounds.push_back(round_of(made.report));
      remesh_ms += made.report.remesh_ms, fit_ms += made.report.fit_ms, measure_ms += made.report.measure_ms;
      if (better_round(rounds.back(), rounds[static_cast<std::size_t>(kept)], tolerance)) {
        out = std::move(made);
        features = std::move(round_features);
        kept = static_cast<int>(rounds.size()) - 1;
      }
    } catch (const Error& e) {
      if (e.kind() == ErrorKind::Usage) throw;  // cancelled
      MeshPathRound failed;
      failed.target_faces = ro.target_faces;
      failed.failure = e.what();
      rounds.push_back(failed);
    }
    if (coarser) break;  // one coarser round at most
  }

  MeshPathReport& rep = out.report;
  rep.input_vertices = tri.num_vertices();
  rep.input_triangles = tri.num_faces();
  rep.feature_angle = settings.feature_angle;
  rep.size_rule = size_rule;
  rep.fit_tolerance = tolerance;
  rep.rounds = std::move(rounds);
  rep.kept_round = kept;
  rep.remesh_ms = remesh_ms, rep.fit_ms = fit_ms, rep.measure_ms = measure_ms;
  const MeshPathRound& best = rep.rounds[static_cast<std::size_t>(kept)];
  rep.tolerance_met = !(tolerance > 0) || best.distance() <= tolerance;
  rep.predicted_target_faces = rep.tolerance_met ? 0 : predicted;
  if (!rep.tolerance_met) {
    const std::size_t n = rep.rounds.size();
    std::string warning = "subd2nurbs: warning: the fit tolerance " + short_number(tolerance) + " was not met: " +
                  (n == 1 ? std::string("the cage") : "the closest of " + std::to_string(n) + " cages") + " (" +
                  std::to_string(best.quads) + " quads) is within " + short_number(best.distance()) +
                  " of the diagonal (to the mesh " + short_number(best.to_mesh) + ", from it " +
                  short_number(best.from_mesh) + ")";
    if (predicted > 0)
      warning += "; the size rule predicts about " + std::to_string(predicted) + " quads for it, more than " +
                     short_number(kMaxSizeFactor) + " x the automatic size, so they were not tried";
    warning += " (a target face count given sets the size)";
    rep.warnings.push_back(warning);
  }

  // The kept features' normal angles against the mesh's dihedrals.
  Diagnostics ignore;
  const PolyMesh poly = PolyMesh::build(tri.num_vertices(), tri.face_sizes, tri.face_indices, &ignore);
  rep.feature_angles = measure_feature_angles(out.cage.level, out.positions, mesh_feature_edges(tri, poly, features),
                                             out.sector_edges);
  const FeatureAngleStats& fa = rep.feature_angles;
  if (fa.max_difference > kFoldedCreaseDegrees)
    rep.warnings.push_back("subd2nurbs: warning: a feature curve folds: the surface's normal angle across it differs "
                           "from the mesh's dihedral by " + short_number(fa.max_difference) + " degrees at (" +
                           short_number(fa.where[0]) + ", " + short_number(fa.where[1]) + ", " +
                           short_number(fa.where[2]) + "); another size of the cage (a target face count) may "
                           "avoid it");
  return out;
}

void write_mesh_path(JsonWriter& w, const MeshPathReport& r) {
  w.begin_object();
  w.members("reason", r.route.reason, "input_vertices", r.input_vertices, "input_triangles", r.input_triangles);
  w.key("features").begin_object();
  w.members("angle_deg", r.feature_angle, "edges", r.feature_edges_in, "corners", r.corners_in, "chains",
            r.feature_chains_in, "faded_edges", r.faded_edges_in, "fading_ends", r.fading_ends_in, "plane_edges",
            r.plane_edges_in);
  w.end_object();
  w.key("cage");
  write_stats(w, r.remesh);
  w.members("target_faces", r.target_faces, "edge_length", r.edge_length);
  w.key("size").begin_object();
  w.members("rule", r.size_rule, "fit_tolerance", r.fit_tolerance, "tolerance_met", r.tolerance_met, "kept_round",
            r.kept_round, "predicted_target_faces", r.predicted_target_faces);
  w.key("rounds").begin_array();
  for (const MeshPathRound& round : r.rounds) {
    w.begin_object();
    w.members("target_faces", round.target_faces, "quads", round.quads, "limit_to_target_max", round.to_mesh,
              "target_to_limit_max", round.from_mesh, "ms", round.ms, "remesh_ms", round.remesh_ms);
    if (!round.failure.empty()) w.member("failure", round.failure);
    w.end_object();
  }
  w.end_array();
  w.end_object();
  w.key("fit").begin_object();
  w.members("iterations", r.fit.fit.iterations, "stop", std::string(to_string(r.fit.fit.stop)));
  w.key("before");
  write_target_distance(w, r.fit.before);
  w.key("after");
  write_target_distance(w, r.fit.after);
  w.end_object();
  w.key("feature_angles").begin_object();
  w.members("samples", r.feature_angles.samples, "max_difference_deg", r.feature_angles.max_difference,
            "mean_difference_deg", r.feature_angles.mean_difference, "where_edge", r.feature_angles.where_edge);
  if (r.feature_angles.samples > 0) w.key("where").point(r.feature_angles.where);
  w.end_object();
  w.key("planar").begin_object();
  w.members("regions", r.planar.regions, "regions_used", r.planar.regions_used, "faces", r.planar.faces,
            "faces_off_plane", r.planar.faces_off_plane, "faces_dropped", r.planar.faces_dropped, "vertices_moved", r.planar.vertices_moved);
  w.members("max_move", r.planar.max_move, "flatness_before", r.planar.flatness_before, "flatness_after",
            r.planar.flatness_after);
  w.members("vertices_free", r.planar.vertices_free, "vertices_untangled", r.planar.vertices_untangled,
            "faces_folded_before", r.planar.faces_folded_before, "faces_folded_after", r.planar.faces_folded_after);
  w.end_object();
  w.key("ms").begin_object();
  w.members("remesh", r.remesh_ms, "fit", r.fit_ms, "measure", r.measure_ms);
  w.end_object();
  w.end_object();
}

std::string mesh_path_summary(const MeshPathReport& r) {
  std::ostringstream o;
  const QuadRemeshStats& c = r.remesh;
  o << "  mesh       " << r.input_triangles << " triangles, " << r.feature_edges_in << " feature edges in "
    << r.feature_chains_in << " curves, " << r.corners_in << " corners (feature angle " << short_number(r.feature_angle)
    << " deg)";
  if (r.plane_edges_in > 0) o << "; " << r.plane_edges_in << " where planes end on fillets narrower than the cage";
  if (r.faded_edges_in > 0)
    o << "; " << r.faded_edges_in << " of the edges continue creases that fade below it, " << r.fading_ends_in
      << (r.fading_ends_in == 1 ? " fading end" : " fading ends");
  o << "\n";
  o << "  cage       " << c.faces << " quads, " << c.extraordinary_vertices << " extraordinary vertices, "
    << c.feature_edges << " feature edges kept, remeshed in " << short_number(r.remesh_ms / 1000) << " s\n";
  o << "  fit        " << r.fit.fit.iterations << " iterations (" << to_string(r.fit.fit.stop) << "), to the mesh: "
    << distance_text(r.fit.after.limit_to_target) << "; from the mesh: " << distance_text(r.fit.after.target_to_limit)
    << " (of the diagonal)\n";
  if (r.size_rule == "fit_tolerance") {
    o << "  size       ";
    if (r.rounds.size() == 1) o << "one round, ";
    else o << r.rounds.size() << " rounds (";
    for (std::size_t i = 0; r.rounds.size() > 1 && i < r.rounds.size(); ++i) {
      const MeshPathRound& round = r.rounds[i];
      o << (i ? ", " : "") << round.quads << " quads: ";
      if (round.failure.empty()) o << short_number(round.distance());
      else o << "failed";
      if (static_cast<int>(i) == r.kept_round) o << " kept";
    }
    if (r.rounds.size() > 1) o << "), ";
    o << "fit tolerance " << short_number(r.fit_tolerance) << (r.tolerance_met ? " met" : " NOT met");
    if (r.predicted_target_faces > 0) o << " (about " << r.predicted_target_faces << " quads predicted for it, not tried)";
    o << "\n";
  }
  if (r.feature_angles.samples > 0)
    o << "  features   normal angle across kept feature curves within " << short_number(r.feature_angles.max_difference)
      << " deg of the mesh's dihedral (mean " << short_number(r.feature_angles.mean_difference) << ")\n";
  if (r.planar.faces > 0)
    o << "  planar     " << r.planar.faces << " cage faces in " << r.planar.regions_used << " of " << r.planar.regions
      << " planar regions flat within " << short_number(r.planar.flatness_after) << " of the diagonal (fit: "
      << short_number(r.planar.flatness_before) << ")\n";
  return o.str();
}

}  // namespace subd2nurbs::pipeline
