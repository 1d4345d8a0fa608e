// The corpus -> B-rep check shared by the convert tests: build the patches of one corpus shape
// at the default level, build the B-rep, and measure it with OCCT. The expected counts are
// computed from the cage alone (face sizes, hole flags, edges), not from the PatchSet.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <BRep_Builder.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Compound.hxx>

#include "converter/occt/brep_builder.h"
#include "converter/occt/shape_check.h"
#include "core/patch/packing.h"
#include "core/patch/patch_builder.h"
#include "core/polar/polar_structure.h"
#include "io/obj_reader.h"
#include "common/corpus.h"

namespace subd2nurbs::testing {

inline std::string corpus_file(const std::string& shape) {
  return std::string(SUBD2NURBS_CORPUS_DIR) + "/" + shape + ".obj";
}

/// Every corpus shape that validation accepts (all but non_manifold_corpus_shapes()), sorted.
inline std::vector<std::string> manifold_corpus_shapes() {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(SUBD2NURBS_CORPUS_DIR)) {
    if (entry.path().extension() != ".obj") continue;
    const std::string name = entry.path().stem().string();
    if (non_manifold_corpus_shapes().count(name) == 0) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

/// What the cage alone says the B-rep must be.
struct ExpectedBrep {
  int faces = 0;       ///< quads of the coarsest all-quad mesh that are not holes
  int free_edges = 0;  ///< edges of that mesh with exactly one non-hole face
  bool closed = false; ///< no boundary edge and no hole: one solid per component
  int components = 0;  ///< of the non-hole faces, connected across edges
  int closed_components = 0;  ///< components none of whose edges has a single non-hole face
  double diagonal = 0; ///< bounding-box diagonal of the cage's vertices
};

/// Counts from the MeshInput's faces and the base level's hole flags (which include the faces
/// that BoundaryRule::None removes). The coarsest all-quad mesh is the cage when every face
/// (holes included) is a quad, else level 1, where each face of size n becomes n quads that
/// inherit its hole flag and each cage edge becomes two edges.
/// Polar structures (`caps`, from detect_polar_structures) replace their triangles and 1-layer
/// quads by one face each, and those faces do not count when deciding whether the cage is all
/// quads.
inline ExpectedBrep expected_brep(const MeshInput& in, const std::vector<char>& face_hole,
                                  const std::vector<PolarStructure>& caps = {}) {
  ExpectedBrep e;
  std::vector<char> cap_face(in.num_faces(), 0);
  for (const PolarStructure& s : caps)
    for (int f : s.cap_faces) cap_face[f] = 1;
  bool all_quads = true;
  for (int f = 0; f < in.num_faces(); ++f) all_quads = all_quads && (cap_face[f] || in.face_sizes[f] == 4);
  e.faces += static_cast<int>(caps.size());
  std::map<std::pair<int, int>, int> live_faces_on_edge;  // undirected cage edge -> non-hole faces
  bool any_hole = false;
  for (int f = 0, begin = 0; f < in.num_faces(); begin += in.face_sizes[f], ++f) {
    const int n = in.face_sizes[f];
    const bool hole = face_hole[f] != 0;
    any_hole = any_hole || hole;
    if (!hole && !cap_face[f]) e.faces += all_quads ? 1 : n;
    for (int i = 0; i < n; ++i) {
      const int a = in.face_indices[begin + i], b = in.face_indices[begin + (i + 1) % n];
      int& count = live_faces_on_edge[{std::min(a, b), std::max(a, b)}];
      if (!hole) ++count;
    }
  }
  // Components: union-find over non-hole faces sharing an edge (level-1 faces of one cage
  // face are connected, and adjacency across cage edges is unchanged, so the cage decides).
  std::vector<int> parent(in.num_faces());
  for (int f = 0; f < in.num_faces(); ++f) parent[f] = f;
  auto find = [&](int f) { while (parent[f] != f) f = parent[f] = parent[parent[f]]; return f; };
  std::map<std::pair<int, int>, int> first_face;
  for (int f = 0, begin = 0; f < in.num_faces(); begin += in.face_sizes[f], ++f) {
    if (face_hole[f]) continue;
    for (int i = 0, n = in.face_sizes[f]; i < n; ++i) {
      const int a = in.face_indices[begin + i], b = in.face_indices[begin + (i + 1) % n];
      const auto [it, inserted] = first_face.insert({{std::min(a, b), std::max(a, b)}, f});
      if (!inserted) parent[find(f)] = find(it->second);
    }
  }
  for (int f = 0; f < in.num_faces(); ++f) e.components += !face_hole[f] && find(f) == f;
  {  // A component is closed when none of its faces has an edge with one non-hole face.
    std::set<int> open_roots;
    for (int f = 0, begin = 0; f < in.num_faces(); begin += in.face_sizes[f], ++f) {
      if (face_hole[f]) continue;
      for (int i = 0, n = in.face_sizes[f]; i < n; ++i) {
        const int a = in.face_indices[begin + i], b = in.face_indices[begin + (i + 1) % n];
        if (live_faces_on_edge[{std::min(a, b), std::max(a, b)}] == 1) open_roots.insert(find(f));
      }
    }
    e.closed_components = e.components - static_cast<int>(open_roots.size());
  }

  bool any_boundary = false;
  for (const auto& [edge, count] : live_faces_on_edge) {
    (void)edge;
    if (count == 1) e.free_edges += all_quads ? 1 : 2;
  }
  // A cage edge with a single face (hole or not) is an open boundary of the cage.
  std::map<std::pair<int, int>, int> faces_on_edge;
  for (int f = 0, begin = 0; f < in.num_faces(); begin += in.face_sizes[f], ++f)
    for (int i = 0, n = in.face_sizes[f]; i < n; ++i) {
      const int a = in.face_indices[begin + i], b = in.face_indices[begin + (i + 1) % n];
      ++faces_on_edge[{std::min(a, b), std::max(a, b)}];
    }
  for (const auto& [edge, count] : faces_on_edge) any_boundary = any_boundary || count == 1;
  e.closed = !any_boundary && !any_hole;

  std::array<double, 3> lo = in.positions.at(0), hi = lo;
  for (const auto& p : in.positions)
    for (int k = 0; k < 3; ++k) { lo[k] = std::min(lo[k], p[k]); hi[k] = std::max(hi[k], p[k]); }
  e.diagonal = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                         (hi[2] - lo[2]) * (hi[2] - lo[2]));
  return e;
}

/// Edges of the curves shared by two patches: those the PatchSet claims G1, C1 or C2 (which
/// must be smooth) or the others (C0: sharp creases and approximate rays).
inline std::vector<TopoDS_Shape> shared_edges(const PatchSet& ps, const occt::BrepResult& brep,
                                              bool smooth) {
  std::vector<TopoDS_Shape> edges;
  for (size_t c = 0; c < ps.curves.size(); ++c) {
    const Continuity k = ps.curves[c].continuity;
    if (ps.curves[c].uses.size() != 2) continue;
    const bool is_smooth = k == Continuity::G1 || k == Continuity::C1 || k == Continuity::C2;
    if (is_smooth == smooth) edges.push_back(brep.curve_edges.at(c));
  }
  return edges;
}

/// A compound of the faces of `shape` that contain one of `edges` (sharing their TShapes, so
/// summarize() finds the same edges between the same faces in it).
inline TopoDS_Shape faces_along(const TopoDS_Shape& shape, const std::vector<TopoDS_Shape>& edges) {
  TopTools_IndexedDataMapOfShapeListOfShape ancestors;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, ancestors);
  TopTools_IndexedMapOfShape faces;
  for (const TopoDS_Shape& e : edges) {
    const int index = ancestors.FindIndex(e);
    if (index == 0) continue;
    for (const TopoDS_Shape& f : ancestors(index)) faces.Add(f);
  }
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  for (int i = 1; i <= faces.Extent(); ++i) builder.Add(compound, faces(i));
  return compound;
}

/// One shape through the pipeline, with everything the tests assert on.
struct CorpusBrep {
  ExpectedBrep expected;
  PatchBuild build;
  PackedSet packed;  ///< the faces that were built: packed (corpus_brep(..., packed = true)) or build.set as is
  occt::BrepResult brep;
  /// The whole shape (counts, free edges, validity), measured along the smooth edges only.
  occt::ShapeSummary smooth;
  /// The faces along the other shared edges (C0 curves), measured along those edges: the
  /// gaps there. (Measuring the whole shape twice would integrate its area twice, which is
  /// what summarize() spends its time on.)
  occt::ShapeSummary sharp;
  int smooth_edge_count = 0, sharp_edge_count = 0;
  double max_gap() const { return std::max(smooth.max_gap, sharp.max_gap); }
  double seconds = 0;  ///< the whole check
  double patch_seconds = 0, brep_seconds = 0, summary_seconds = 0;
};

inline CorpusBrep corpus_brep(const std::string& shape, int samples_per_edge = 16, bool packed = false) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  CorpusBrep r;
  const LoadedCage cage = read_obj(corpus_file(shape));
  const SubdivLevel base = SubdivLevel::from_input(cage.input);
  r.expected = expected_brep(cage.input, base.face_hole, detect_polar_structures(base).structures);
  auto t = Clock::now();
  r.build = build_patches(base, std::vector<Point3>(cage.input.positions.begin(), cage.input.positions.end()));
  r.packed = packed ? pack_patches(r.build) : unpacked(r.build.set);
  r.patch_seconds = since(t);
  t = Clock::now();
  r.brep = occt::build_brep(r.packed.set);
  r.brep_seconds = since(t);
  t = Clock::now();
  const std::vector<TopoDS_Shape> smooth = shared_edges(r.packed.set, r.brep, true);
  const std::vector<TopoDS_Shape> sharp = shared_edges(r.packed.set, r.brep, false);
  r.smooth_edge_count = static_cast<int>(smooth.size());
  r.sharp_edge_count = static_cast<int>(sharp.size());
  r.smooth = occt::summarize(r.brep.shape, smooth, samples_per_edge, /*mass_properties=*/false);
  if (!sharp.empty()) r.sharp = occt::summarize(faces_along(r.brep.shape, sharp), sharp, samples_per_edge, /*mass_properties=*/false);
  r.summary_seconds = since(t);
  r.seconds = since(start);
  return r;
}

}  // namespace subd2nurbs::testing
