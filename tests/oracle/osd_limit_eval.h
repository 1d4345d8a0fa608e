// OpenSubdiv's limit surface as an evaluation oracle: adaptive refinement, a double-precision
// Far::PatchTable with Gregory-basis end caps, and Far::PatchMap lookup by ptex face.
//
// Ptex convention (OpenSubdiv's): a quad face is one ptex face, (u, v) in [0,1]^2 with (0,0)
// at the face's first vertex and u running along its first edge (towards the second vertex).
// For an all-quad mesh the ptex face of face f is f. An n-gon (n != 4) is split into n ptex
// faces, one per corner, numbered consecutively (see Far::PtexIndices).
//
// Where the returned patch is REGULAR it is an exact bicubic B-spline patch of the limit
// surface (a subpatch of the adaptive refinement; along boundaries and infinitely sharp
// creases with OpenSubdiv's sharp-side rule). Elsewhere (the 2^-level neighbourhood of an
// extraordinary vertex, or of a smooth corner) it is a Gregory end cap, which only
// approximates the limit surface; its corner is the exact limit position except at darts,
// where OpenSubdiv uses the smooth limit mask (see docs/architecture.md).
// Options: adaptive refinement to the isolation level, useInfSharpPatch on and legacy
// sharp-corner patches off (so that REGULAR means exact), double-precision patch stencils.
#pragma once

#include <memory>

#include "core/mesh/mesh_input.h"
#include "core/util/point3.h"

namespace subd2nurbs::testing {

class OsdLimitEvaluator {
 public:
  /// Builds the patch table of `input` (tags and options as osd_create_refiner), isolating
  /// features to `isolation_level` (1..10). If OpenSubdiv rejects the topology ok() is false.
  explicit OsdLimitEvaluator(const MeshInput& input, int isolation_level = 10);
  ~OsdLimitEvaluator();
  OsdLimitEvaluator(OsdLimitEvaluator&&) noexcept;
  OsdLimitEvaluator& operator=(OsdLimitEvaluator&&) noexcept;

  bool ok() const;

  struct Sample {
    Point3 p{}, du{}, dv{};       ///< position and derivatives with respect to the ptex (u, v)
    bool regular_patch = false;   ///< the patch hit is REGULAR (exact B-spline), not an end cap
  };

  /// Limit position and first derivatives at (u, v) of a ptex face.
  /// \throw std::out_of_range if !ok(), the ptex face does not exist, or it has no patch
  /// (a hole, or a face removed by BoundaryRule::None).
  Sample eval(int ptex_face, double u, double v) const;

  int num_ptex_faces() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace subd2nurbs::testing
