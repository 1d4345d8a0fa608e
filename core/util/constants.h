// Mathematical constants shared by the geometry core.
#pragma once

namespace subd2nurbs {

/// pi, the nearest double (the value std::acos(-1.0) returns).
constexpr double kPi = 3.14159265358979323846;

}  // namespace subd2nurbs
