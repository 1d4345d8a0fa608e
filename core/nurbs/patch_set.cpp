#include "core/nurbs/patch_set.h"

#include <numeric>

namespace subd2nurbs {

const char* to_string(PatchKind kind) {
  switch (kind) {
    case PatchKind::RegularBSpline: return "regular";
    case PatchKind::Pccm: return "pccm";
    case PatchKind::PolarCap: return "polar_cap";
  }
  return "?";
}

const char* to_string(Continuity c) {
  switch (c) {
    case Continuity::Boundary: return "boundary";
    case Continuity::C0: return "C0";
    case Continuity::G1: return "G1";
    case Continuity::C1: return "C1";
    case Continuity::C2: return "C2";
  }
  return "?";
}

int KnotVector::num_poles(int degree) const {
  return std::accumulate(mults.begin(), mults.end(), 0) - degree - 1;
}

std::vector<double> KnotVector::flat() const {
  std::vector<double> out;
  for (size_t i = 0; i < knots.size(); ++i) out.insert(out.end(), mults[i], knots[i]);
  return out;
}

}  // namespace subd2nurbs
