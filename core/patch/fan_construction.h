// Construction Q around an irregular vertex, per fan of faces between its sharp edges
// (docs/patches.md, "Irregular vertices: fans"): bicubic Bezier nets of the level-k quads at
// the vertex that interpolate the limit point, share the limit tangent plane there, are exactly G1 across
// the smooth rays and C1 with the regular surface around the 2x2 zone of each sector.
#pragma once

#include <array>
#include <vector>

#include "core/patch/patch_builder.h"  // FanMode
#include "core/patch/regular_net.h"

namespace subd2nurbs {

enum class RayKind : unsigned char {
  G1,           ///< smooth ray between two sectors: exactly G1
  Cut,          ///< two sectors, constructed quadratic, no G1 claim (dart's sharp ray, approx.)
  ExactEnd,     ///< end of an open fan: a sharp edge whose limit curve is known exactly
};

struct Fan {
  int v = -1;
  std::vector<int> sectors;  ///< corner at v of each sector's quad (0,0), counter-clockwise
  bool cyclic = false;
  FanMode mode = FanMode::Smooth;
};

class FanBuilder {
 public:
  FanBuilder(const LevelView& L, const Point3& limit, std::vector<Point3>& nets)
      : L_(L), m_(L.m), limit_(limit), nets_(nets) {}

  // Builds the fan's nets; returns the G1 coefficient c and fills ray kinds.
  double build(const Fan& fan, std::vector<RayKind>& kinds, std::vector<int>& ray_edges);

 private:
  using V3 = Eigen::Vector3d;
  V3& B(int s, int i, int j) { return B_[s][i][j]; }
  int nS() const { return static_cast<int>(B_.size()); }
  int nR() const { return cyclic_ ? nS() : nS() + 1; }
  // Sector owning ray r as its x axis (-1 for the end ray of an open fan).
  int x_sector(int r) const { return r < nS() ? r : -1; }
  // Sector owning ray r as its y axis (-1 for ray 0 of an open fan).
  int y_sector(int r) const { return cyclic_ ? (r + nS() - 1) % nS() : r - 1; }
  V3 ray(int r, int i) {
    const int s = x_sector(r);
    return s >= 0 ? B(s, i, 0) : B(y_sector(r), 0, i);
  }
  void set_ray(int r, int i, const V3& p) {
    if (const int s = x_sector(r); s >= 0) B(s, i, 0) = p;
    if (const int s = y_sector(r); s >= 0) B(s, 0, i) = p;
  }
  void add_to_ray_block(int r, const V3& d);

  const LevelView& L_;
  const PolyMesh& m_;
  Point3 limit_;
  std::vector<Point3>& nets_;
  bool cyclic_ = false;
  std::vector<std::array<std::array<V3, 7>, 7>> B_;
};


/// Fans of vertex v: maximal runs of faces between sharp rays (one cyclic fan if it has no
/// sharp ray). Fans that are regular for all their faces are not listed.
std::vector<Fan> fans_at(const LevelView& L, int v);

}  // namespace subd2nurbs
