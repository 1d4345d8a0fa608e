#include "osd_reference.h"

#include <algorithm>
#include <cmath>

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

namespace subd2nurbs::testing {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

namespace {


Sdc::Options sdc_options(const SubdivOptions& o) {
  Sdc::Options opt;
  switch (o.boundary) {
    case BoundaryRule::None: opt.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_NONE); break;
    case BoundaryRule::EdgeOnly: opt.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY); break;
    case BoundaryRule::EdgeAndCorner:
      opt.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
      break;
  }
  opt.SetCreasingMethod(o.crease_method == CreaseMethod::Chaikin ? Sdc::Options::CREASE_CHAIKIN
                                                                 : Sdc::Options::CREASE_UNIFORM);
  opt.SetTriangleSubdivision(o.triangles == TriangleRule::Smooth ? Sdc::Options::TRI_SUB_SMOOTH
                                                                 : Sdc::Options::TRI_SUB_CATMARK);
  return opt;
}

}  // namespace

std::unique_ptr<Far::TopologyRefiner> osd_create_refiner(const MeshInput& in) {
  Far::TopologyDescriptor desc;
  desc.numVertices = in.num_vertices();
  desc.numFaces = in.num_faces();
  desc.numVertsPerFace = in.face_sizes.data();
  desc.vertIndicesPerFace = in.face_indices.data();
  std::vector<int> crease_verts;
  std::vector<float> crease_sharp;
  for (const CreaseTag& c : in.creases) {
    crease_verts.push_back(c.v0);
    crease_verts.push_back(c.v1);
    crease_sharp.push_back(static_cast<float>(c.sharpness));
  }
  desc.numCreases = static_cast<int>(in.creases.size());
  desc.creaseVertexIndexPairs = crease_verts.data();
  desc.creaseWeights = crease_sharp.data();
  std::vector<int> corner_verts;
  std::vector<float> corner_sharp;
  for (const CornerTag& c : in.corners) {
    corner_verts.push_back(c.vertex);
    corner_sharp.push_back(static_cast<float>(c.sharpness));
  }
  desc.numCorners = static_cast<int>(in.corners.size());
  desc.cornerVertexIndices = corner_verts.data();
  desc.cornerWeights = corner_sharp.data();
  desc.numHoles = static_cast<int>(in.holes.size());
  desc.holeIndices = in.holes.data();

  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  Factory::Options fopt(Sdc::SCHEME_CATMARK, sdc_options(in.options));
  return std::unique_ptr<Far::TopologyRefiner>(Factory::Create(desc, fopt));
}

OsdRefinement osd_refine(const MeshInput& in, int levels, bool with_limit) {
  OsdRefinement out;
  out.refiner = osd_create_refiner(in);
  if (!out.refiner) return out;
  Far::TopologyRefiner::UniformOptions uopt(levels);
  uopt.fullTopologyInLastLevel = true;
  out.refiner->RefineUniform(uopt);

  std::vector<std::vector<Vertex3>> buf(levels + 1);
  buf[0].resize(in.num_vertices());
  for (int v = 0; v < in.num_vertices(); ++v)
    for (int k = 0; k < 3; ++k) buf[0][v].p[k] = in.positions[v][k];
  Far::PrimvarRefinerReal<double> primvar(*out.refiner);
  for (int l = 1; l <= levels; ++l) {
    buf[l].resize(out.refiner->GetLevel(l).GetNumVertices());
    primvar.Interpolate(l, buf[l - 1], buf[l]);
  }
  auto to_points = [](const std::vector<Vertex3>& b) {
    std::vector<Point3> p(b.size());
    for (size_t i = 0; i < b.size(); ++i) p[i] = {b[i].p[0], b[i].p[1], b[i].p[2]};
    return p;
  };
  for (int l = 0; l <= levels; ++l) out.positions.push_back(to_points(buf[l]));
  if (with_limit) {
    std::vector<Vertex3> lim(buf[levels].size());
    primvar.Limit(buf[levels], lim);
    out.limit = to_points(lim);
  }
  return out;
}

OsdMapping map_to_osd(const Refinement& ours, const Far::TopologyRefiner& theirs) {
  OsdMapping m;
  const int levels = static_cast<int>(ours.levels.size()) - 1;
  m.vertex.resize(levels + 1);
  m.face.resize(levels + 1);
  const PolyMesh& base = ours.levels[0].mesh;
  for (int v = 0; v < base.num_vertices(); ++v) m.vertex[0].push_back(v);
  for (int f = 0; f < base.num_faces(); ++f) m.face[0].push_back(f);
  for (int l = 0; l < levels; ++l) {
    const PolyMesh& pm = ours.levels[l].mesh;
    const Far::TopologyLevel& tl = theirs.GetLevel(l);
    const auto& vmap = m.vertex[l];
    const auto& fmap = m.face[l];
    std::vector<int>& cv = m.vertex[l + 1];
    cv.assign(ours.levels[l + 1].mesh.num_vertices(), -1);
    for (int v = 0; v < pm.num_vertices(); ++v)
      cv[child_of_vertex(pm, v)] = tl.GetVertexChildVertex(vmap[v]);
    for (int f = 0; f < pm.num_faces(); ++f) cv[child_of_face(pm, f)] = tl.GetFaceChildVertex(fmap[f]);
    for (int e = 0; e < pm.num_edges(); ++e) {
      const int te = tl.FindEdge(vmap[pm.edge_vertex(e, 0)], vmap[pm.edge_vertex(e, 1)]);
      cv[child_of_edge(pm, e)] = te < 0 ? -1 : tl.GetEdgeChildVertex(te);
    }
    std::vector<int>& cf = m.face[l + 1];
    cf.assign(pm.num_corners(), -1);
    for (int f = 0; f < pm.num_faces(); ++f) {
      auto children = tl.GetFaceChildFaces(fmap[f]);
      auto tverts = tl.GetFaceVertices(fmap[f]);
      // Our child face at corner h sits at vertex corner_vertex(h); find theirs at that vertex.
      for (int h = pm.face_begin(f); h < pm.face_end(f); ++h) {
        const int tv = vmap[pm.corner_vertex(h)];
        for (int i = 0; i < tverts.size(); ++i)
          if (tverts[i] == tv && i < children.size()) cf[h] = children[i];
      }
    }
  }
  return m;
}

double bbox_diagonal(const std::vector<Point3>& pts) {
  Point3 lo = pts.at(0), hi = pts.at(0);
  for (const Point3& p : pts)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                   (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

}  // namespace subd2nurbs::testing

namespace subd2nurbs::testing {

OsdComparison compare_with_osd(const MeshInput& input, int levels) {
  OsdComparison r;
  r.levels = levels;
  OsdRefinement osd = osd_refine(input, levels);
  if (!osd.refiner) return r;
  r.osd_accepted = true;
  SubdivLevel base = SubdivLevel::from_input(input);
  Refinement ours = refine_uniform(base, levels);
  std::vector<Point3> base_points(input.positions.begin(), input.positions.end());
  auto pos = ours.positions(base_points);
  const double diag = bbox_diagonal(base_points);
  OsdMapping map = map_to_osd(ours, *osd.refiner);
  auto note = [&](const std::string& s) {
    if (r.first_problem.empty()) r.first_problem = s;
  };
  for (int l = 0; l <= levels; ++l) {
    const SubdivLevel& lv = ours.levels[l];
    const PolyMesh& m = lv.mesh;
    const auto& tl = osd.refiner->GetLevel(l);
    if (m.num_vertices() != tl.GetNumVertices() || m.num_faces() != tl.GetNumFaces()) {
      ++r.count_mismatches;
      note("level " + std::to_string(l) + ": counts differ (ours " + std::to_string(m.num_vertices()) +
           " vertices, " + std::to_string(m.num_faces()) + " faces; OpenSubdiv " +
           std::to_string(tl.GetNumVertices()) + ", " + std::to_string(tl.GetNumFaces()) + ")");
      continue;
    }
    for (int v = 0; v < m.num_vertices(); ++v) {
      const int t = map.vertex[l][v];
      if (t < 0) {
        ++r.unmapped;
        note("level " + std::to_string(l) + ": vertex " + std::to_string(v) + " unmapped");
        continue;
      }
      double err = 0;
      for (int k = 0; k < 3; ++k) err = std::max(err, std::abs(pos[l][v][k] - osd.positions[l][t][k]));
      if (err / diag > r.max_relative_error) {
        r.max_relative_error = err / diag;
      }
      if (lv.vertex_sharpness[v] != tl.GetVertexSharpness(t)) {
        ++r.sharpness_mismatches;
        note("level " + std::to_string(l) + ": vertex " + std::to_string(v) + " sharpness " +
             std::to_string(lv.vertex_sharpness[v]) + " vs " + std::to_string(tl.GetVertexSharpness(t)));
      }
    }
    for (int e = 0; e < m.num_edges(); ++e) {
      const int a = map.vertex[l][m.edge_vertex(e, 0)], b = map.vertex[l][m.edge_vertex(e, 1)];
      const int te = (a < 0 || b < 0) ? -1 : tl.FindEdge(a, b);
      if (te < 0) {
        ++r.unmapped;
        note("level " + std::to_string(l) + ": edge " + std::to_string(e) + " not found in OpenSubdiv");
      } else if (lv.edge_sharpness[e] != tl.GetEdgeSharpness(te)) {
        ++r.sharpness_mismatches;
        note("level " + std::to_string(l) + ": edge " + std::to_string(e) + " sharpness " +
             std::to_string(lv.edge_sharpness[e]) + " vs " + std::to_string(tl.GetEdgeSharpness(te)));
      }
    }
    for (int f = 0; f < m.num_faces(); ++f) {
      const int tf = map.face[l][f];
      if (tf < 0) {
        ++r.unmapped;
        note("level " + std::to_string(l) + ": face " + std::to_string(f) + " unmapped");
        continue;
      }
      auto tv = tl.GetFaceVertices(tf);
      const int n = m.face_size(f);
      bool same = tv.size() == n;
      if (same) {  // same cycle up to rotation
        int shift = -1;
        for (int i = 0; i < n; ++i)
          if (tv[i] == map.vertex[l][m.face_vertices(f)[0]]) shift = i;
        same = shift >= 0;
        for (int i = 0; same && i < n; ++i)
          same = tv[(shift + i) % n] == map.vertex[l][m.face_vertices(f)[i]];
      }
      if (!same) {
        ++r.face_mismatches;
        note("level " + std::to_string(l) + ": face " + std::to_string(f) + " has different vertices");
      }
      if (static_cast<bool>(lv.face_hole[f]) != tl.IsFaceHole(tf)) {
        ++r.hole_mismatches;
        note("level " + std::to_string(l) + ": face " + std::to_string(f) + " hole flag differs");
      }
    }
  }
  return r;
}

}  // namespace subd2nurbs::testing

namespace subd2nurbs::testing {
LimitErrors limit_error_vs_osd(const MeshInput& input, int extra_levels) {
  SubdivLevel base = SubdivLevel::from_input(input);
  const int levels = static_cast<int>(std::ceil(base.max_semi_sharpness())) + 1 + extra_levels;
  OsdRefinement osd = osd_refine(input, levels, /*with_limit=*/true);
  LimitErrors out;
  if (!osd.refiner) return out;
  Refinement ours = refine_uniform(base, levels);
  OsdMapping map = map_to_osd(ours, *osd.refiner);
  std::vector<Point3> pts(input.positions.begin(), input.positions.end()), lim;
  limit_stencils(base).apply(pts, lim);
  const double diag = bbox_diagonal(pts);
  // Classify at the level OpenSubdiv evaluates (rules there are the ones its Limit() uses).
  const SubdivLevel& last = ours.levels[levels];
  for (int v = 0; v < base.mesh.num_vertices(); ++v) {
    if (base.mesh.is_unused_vertex(v)) continue;
    const Point3& q = osd.limit[map.vertex[levels][v]];
    double err = 0;
    for (int k = 0; k < 3; ++k) err = std::max(err, std::abs(lim[v][k] - q[k]) / diag);
    const VertexRule rule = vertex_rule(last, v);
    const bool special = rule == VertexRule::Dart ||
                         (rule == VertexRule::Smooth && last.mesh.vertex_face_count(v) == 2);
    double& slot = special ? out.special : out.regular;
    slot = std::max(slot, err);
  }
  return out;
}
}  // namespace subd2nurbs::testing
