// Detection of polar structures (docs/math.md 3.1; Myles-Karciauskas-Peters 2008, section 1.1).
//
// A polar vertex is an interior vertex whose incident faces are all triangles. It is a polar
// structure when its 1-layer and 2-layer are quads and its 1-link and 2-link vertices are all
// 4-valent: rings 0..3 as below, with ring 3 belonging to the Catmull-Clark region.
//
//   ring 0: the pole;  triangles (pole, ring1[j], ring1[j+1])
//   1-layer quads (ring1[j+1], ring1[j], ring2[j], ring2[j+1])
//   2-layer quads (ring2[j+1], ring2[j], ring3[j], ring3[j+1])
//
// A candidate that fails (too low a valence, a missing layer, a sharp tag or hole inside
// the structure, an overlap with another structure) is reported with the reason and left to
// Catmull-Clark, where it is an extraordinary vertex.
#pragma once

#include <string>
#include <vector>

#include "core/refine/refiner.h"

namespace subd2nurbs {

/// Smallest pole valence BP subdivision supports (docs/math.md 3.4: n < 6 gives unbounded
/// curvature or a non-affine rule).
constexpr int kMinPolarValence = 6;

struct PolarStructure {
  int pole = -1;     ///< vertex index
  int valence = 0;   ///< n
  /// rings[r - 1][j]: vertex of ring r = 1, 2, 3 on spoke j (counter-clockwise).
  std::vector<int> rings[3];
  /// Faces the polar cap replaces: the n triangles (spoke order), then the n 1-layer quads.
  std::vector<int> cap_faces;
  /// The n 2-layer quads (spoke order): Catmull-Clark faces whose limit joins the cap C2.
  std::vector<int> layer2_faces;
};

/// A vertex that looks like a pole (interior, all incident faces triangles, valence >= 3)
/// but is not a polar structure.
struct RejectedPole {
  /// Why: the two cases the separating first step (docs/math.md 3.7, polar_separation.h) can
  /// mend, or anything else about the rings.
  enum class Kind : unsigned char { LowValence, TooClose, Structure };
  int vertex = -1;
  int valence = 0;
  std::string reason;  ///< e.g. "ring-2 vertex 17 has valence 5, polar structures need 4"
  Kind kind = Kind::Structure;
};

struct PolarDetection {
  std::vector<PolarStructure> structures;  ///< in vertex order
  std::vector<RejectedPole> rejected;      ///< in vertex order
};

/// Finds the polar structures of a (base) level. Structures whose rings 0..3 share a vertex
/// are both rejected ("too close"): BP needs the four rings of each to itself.
PolarDetection detect_polar_structures(const SubdivLevel& level, int min_valence = kMinPolarValence);

}  // namespace subd2nurbs
