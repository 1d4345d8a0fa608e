// Facts about OpenSubdiv's regression corpus (tests/data/corpus) that several tests share.
#pragma once

#include <map>
#include <string>

#include "core/mesh/errors.h"

namespace subd2nurbs::testing {

/// The corpus shapes our validation rejects, and why. OpenSubdiv accepts them (it handles
/// non-manifold topology); subd2nurbs needs a 2-manifold cage. Each was checked by hand:
/// catmark_fan has an edge on 3 faces, catmark_gregory_test4 a vertex with two separate fans;
/// the nonman_* shapes are OpenSubdiv's non-manifold tests (edges on many faces, pinched
/// vertices, faces that use one vertex twice).
inline const std::map<std::string, MeshErrorCode>& non_manifold_corpus_shapes() {
  static const std::map<std::string, MeshErrorCode> m = {
      {"catmark_fan", MeshErrorCode::NonManifoldEdge},
      {"catmark_gregory_test4", MeshErrorCode::NonManifoldVertex},
      {"catmark_nonman_edge100", MeshErrorCode::NonManifoldEdge},
      {"catmark_nonman_edges", MeshErrorCode::RepeatedVertexInFace},
      {"catmark_nonman_quadpole8", MeshErrorCode::RepeatedVertexInFace},
      {"catmark_nonman_quadpole64", MeshErrorCode::RepeatedVertexInFace},
      {"catmark_nonman_quadpole360", MeshErrorCode::RepeatedVertexInFace},
      {"catmark_nonman_verts", MeshErrorCode::NonManifoldVertex},
      {"catmark_val2_nonman", MeshErrorCode::NonManifoldEdge},
  };
  return m;
}

}  // namespace subd2nurbs::testing
