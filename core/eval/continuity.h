// Continuity across the shared boundary curves of a PatchSet (docs/math.md section 10): both
// patches are sampled with their own parameters at the same curve parameter. Points where a
// patch has no normal (the pole of a polar cap, at one end of its seam) count for the gap
// only.
#pragma once

#include <vector>

#include "core/nurbs/patch_set.h"

namespace subd2nurbs {

struct CurveMeasure {
  int curve = -1;
  Continuity claimed = Continuity::Boundary;
  double gap = 0;               ///< max |X1 - X2| (model units)
  double normal_angle_deg = 0;  ///< max angle between the two unit normals
  double coplanarity = 0;       ///< max |det[D, E, e']| / (|D||E||e'|), D, E the inward cross derivatives
  double c1_jump = 0;           ///< max |D + E| / max(|D|, |E|)
  double c2_jump = 0;           ///< max |D2_1 - D2_2| / max(|D2_1|, |D2_2|, |D|) (second cross derivatives)
  double worst_s = 0;           ///< curve parameter of the largest normal angle
};

struct ContinuityReport {
  std::vector<CurveMeasure> curves;  ///< every curve used by two patches
  double max_gap = 0;                ///< over all shared curves
  double max_normal_angle_deg = 0;   ///< over curves claimed G1 or smoother
  double max_coplanarity = 0;        ///< over curves claimed G1 or smoother
  double max_c1_jump = 0;            ///< over curves claimed C1 or C2
  double max_c2_jump = 0;            ///< over curves claimed C2
  double max_crease_normal_angle_deg = 0;  ///< over C0 curves (sharp creases, approximate rays)
};

/// Samples every shared curve at `samples` parameters per knot span (endpoints included).
ContinuityReport measure_continuity(const PatchSet& ps, int samples = 24);

/// The same for one curve.
CurveMeasure measure_curve(const PatchSet& ps, int curve, int samples = 24);

}  // namespace subd2nurbs
