// The separating first step (docs/math.md 3.7; Myles-Karciauskas-Peters 2008, section 2): one
// Catmull-Clark step of the whole cage in which the triangles around chosen poles are
// treated as degenerate quads (pole, p_i, p_i+1, pole). Each such pole then has 2n
// triangles around it (valence 3 -> 6, 4 -> 8, 5 -> 10), and poles that were too close to
// each other are one level apart: the level-1 mesh has polar structures there.
//
// Rules at a separated pole (everything else is the ordinary Catmull-Clark step):
//   face point of triangle i:   (2 p0 + p_i + p_i+1) / 4
//   edge points, vertex points: the smooth Catmull-Clark rules with those face points
//   new pole:                   (1 - w) p0 + w m, m the mean of ring 1 (w = 3/8, the BP
//                               pole weight; docs/math.md 3.7 on how it was read)
// and each level-1 quad at the pole, (P0', E_i, F_i, E_i+1), becomes the two triangles
// (P0', E_i, F_i) and (P0', F_i, E_i+1).
#pragma once

#include <string>
#include <vector>

#include "core/refine/refiner.h"

namespace subd2nurbs {

/// Weight of the mean of ring 1 in the new pole (docs/math.md 3.7: w = 3/8, low-medium confidence).
constexpr double kSeparationPoleWeight = 3.0 / 8.0;

/// Empty if the separating step can be applied at vertex `pole`: an interior vertex whose
/// faces are all triangles, whose neighbours are interior, 4-valent and untagged, with no
/// sharp edge at the pole or its neighbours; else the reason.
std::string separation_obstacle(const SubdivLevel& level, int pole);

struct SeparatedLevel {
  SubdivLevel level;              ///< level 1, with the separated poles' triangles
  std::vector<Point3> positions;
  /// Cage face each level-1 face comes from (the faces Catmull-Clark makes, plus the second
  /// triangle of every split quad at the end).
  std::vector<int> cage_face;
};

/// The separating step at `poles` (each must pass separation_obstacle).
/// \throw std::invalid_argument naming a pole that does not
SeparatedLevel separate_poles(const SubdivLevel& base, const std::vector<Point3>& positions,
                              const std::vector<int>& poles, double w = kSeparationPoleWeight);

}  // namespace subd2nurbs
