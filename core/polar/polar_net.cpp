#include "core/polar/polar_net.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/util/constants.h"
#include "core/util/eigen_point.h"

namespace subd2nurbs {
namespace {

using V3 = Eigen::Vector3d;

int wrap(int j, int n) { return ((j % n) + n) % n; }

}  // namespace

const Point3& PolarNet::at(int r, int j) const {
  return r == 0 ? pole : rings[static_cast<size_t>(r - 1) * n + wrap(j, n)];
}
Point3& PolarNet::at(int r, int j) {
  return r == 0 ? pole : rings[static_cast<size_t>(r - 1) * n + wrap(j, n)];
}

PolarNet radial_step(const PolarNet& net, const BpParameters& bp) {
  const int n = net.n, R = net.num_rings();
  if (n < 3 || R < 2) throw std::invalid_argument("radial_step: needs n >= 3 and at least 2 rings");
  PolarNet out;
  out.n = n;
  out.rings.resize(static_cast<size_t>(2 * R - 1) * n);
  const double alpha = bp.alpha(), beta = bp.beta;
  V3 m = V3::Zero();
  for (int j = 0; j < n; ++j) m += to_eigen(net.at(1, j));
  m /= n;
  out.pole = to_point((1 - alpha) * to_eigen(net.pole) + alpha * m);
  // gamma_k = (beta + cos t + cos(2t)/2 + cos(3t)/8) / n, t = 2 pi k / n.
  std::vector<double> gamma(n);
  for (int k = 0; k < n; ++k) {
    const double t = 2 * kPi * k / n;
    gamma[k] = (beta + std::cos(t) + 0.5 * std::cos(2 * t) + 0.125 * std::cos(3 * t)) / n;
  }
  for (int i = 0; i < n; ++i) {
    // Relative to the pole: sum(gamma) = beta exactly, so this is the affine rule.
    V3 s = V3::Zero();
    for (int j = 0; j < n; ++j) s += gamma[wrap(j - i, n)] * (to_eigen(net.at(1, j)) - to_eigen(net.pole));
    out.at(1, i) = to_point(to_eigen(net.pole) + s);
  }
  for (int r = 1; r < R; ++r)
    for (int i = 0; i < n; ++i) {
      const V3 a = to_eigen(net.at(r - 1, i)), b = to_eigen(net.at(r, i)), c = to_eigen(net.at(r + 1, i));
      out.at(2 * r, i) = to_point(0.125 * a + 0.75 * b + 0.125 * c);
      out.at(2 * r + 1, i) = to_point(0.5 * (b + c));
    }
  return out;
}

PolarNet circular_step(const PolarNet& net) {
  const int n = net.n, R = net.num_rings();
  PolarNet out;
  out.n = 2 * n;
  out.pole = net.pole;
  out.rings.resize(static_cast<size_t>(R) * 2 * n);
  for (int r = 1; r <= R; ++r)
    for (int i = 0; i < n; ++i) {
      const V3 a = to_eigen(net.at(r, i - 1)), b = to_eigen(net.at(r, i)), c = to_eigen(net.at(r, i + 1));
      out.at(r, 2 * i) = to_point((a + 6 * b + c) / 8);
      out.at(r, 2 * i + 1) = to_point(0.5 * (b + c));
    }
  return out;
}

Point3 bp_limit_point(const PolarNet& net, const BpParameters& bp) {
  V3 m = V3::Zero();
  for (int j = 0; j < net.n; ++j) m += to_eigen(net.at(1, j));
  m /= net.n;
  const double alpha = bp.alpha(), beta = bp.beta;
  return to_point(((1 - beta) * to_eigen(net.pole) + alpha * m) / (1 - beta + alpha));
}

Point3 bp_limit_normal(const PolarNet& net) {
  V3 t1 = V3::Zero(), t2 = V3::Zero();
  for (int j = 0; j < net.n; ++j) {
    const double t = 2 * kPi * j / net.n;
    const V3 d = to_eigen(net.at(1, j)) - to_eigen(net.pole);  // sum cos = sum sin = 0: same tangents
    t1 += std::cos(t) * d;
    t2 += std::sin(t) * d;
  }
  const V3 nrm = t1.cross(t2);
  return to_point(nrm.norm() > 0 ? V3(nrm.normalized()) : V3::Zero());
}

Point3 bp_grid_limit(const PolarNet& net, int r, int j) {
  if (r < 3 || r + 1 > net.num_rings()) throw std::invalid_argument("bp_grid_limit: ring out of range");
  const double w[3] = {1.0 / 6, 4.0 / 6, 1.0 / 6};
  V3 s = V3::Zero();
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) s += w[a] * w[b] * to_eigen(net.at(r - 1 + a, j - 1 + b));
  return to_point(s);
}

}  // namespace subd2nurbs
