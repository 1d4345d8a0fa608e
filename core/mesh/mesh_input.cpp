#include "core/mesh/mesh_input.h"

namespace subd2nurbs {

const char* to_string(BoundaryRule rule) {
  switch (rule) {
    case BoundaryRule::None: return "none";
    case BoundaryRule::EdgeOnly: return "edge-only";
    case BoundaryRule::EdgeAndCorner: return "edge-and-corner";
  }
  return "?";
}

const char* to_string(CreaseMethod method) { return method == CreaseMethod::Chaikin ? "chaikin" : "uniform"; }

const char* to_string(TriangleRule rule) { return rule == TriangleRule::Smooth ? "smooth" : "catmark"; }

}  // namespace subd2nurbs
