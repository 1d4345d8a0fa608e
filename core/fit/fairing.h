// Fairing energy of the Catmull-Clark limit surface and the fits that use it (docs/fitting.md).
//
// Energy (per coordinate, summed over x, y, z), integrated over the limit surface in ptex
// parameters (each cage quad, and each corner piece of an n-gon, is the unit square):
//
//   E(P) = thin_plate * integral |x_uu|^2 + 2 |x_uv|^2 + |x_vv|^2
//        + membrane   * integral |x_u|^2  + |x_v|^2
//
// It is a quadratic form P^T K P. Method: the cage is refined `levels` times (stencils from
// the cage); every level-k face whose four corners are smooth regular vertices (interior,
// four quads, no sharp edge or vertex tag) is one bicubic B-spline patch of its 16 points,
// and its energy is exact: the B-spline Gram integrals, scaled by 4^k (thin plate) or 1
// (membrane) for the 2^-k parameter size. The remaining level-k faces (those within 2^-k of an
// extraordinary vertex, a boundary, a crease or a dart) are left out; as k grows their share
// of the surface shrinks like 2^-k and the energy converges (measured in the tests). With
// levels = 0 a cage that is regular everywhere gets its exact energy.
#pragma once

#include <Eigen/SparseCore>
#include <vector>

#include "core/fit/interpolate.h"
#include "core/polar/polar_structure.h"
#include "core/refine/refiner.h"

namespace subd2nurbs {

struct EnergyOptions {
  double thin_plate = 1.0;
  double membrane = 0.0;
  int levels = 2;  ///< refinement levels for the irregular regions (0..4)
};

/// The 16 x 16 Gram matrix of one uniform bicubic B-spline patch on the unit square for the
/// energy above, control points G[i][j] ordered i + 4 j (i along u).
Eigen::Matrix<double, 16, 16> bicubic_energy_gram(double thin_plate, double membrane);

/// K with E(P) = sum_c P_c^T K P_c over the cage's vertices (symmetric positive semi-definite).
Eigen::SparseMatrix<double> energy_matrix(const SubdivLevel& level, const EnergyOptions& options = {});

/// E(P) for a matrix from energy_matrix.
double energy(const Eigen::SparseMatrix<double>& K, const std::vector<Point3>& positions);

/// Which cage vertices a fairing keeps fixed.
struct KeepSet {
  bool boundary = false;  ///< vertices on the boundary
  bool creases = false;   ///< ends of tagged crease edges (sharpness > 0, not boundary)
  bool tagged = false;    ///< creases, and vertices with a corner tag (vertex sharpness > 0)
};
std::vector<char> kept_vertices(const SubdivLevel& level, const KeepSet& keep);

struct FairOptions {
  EnergyOptions energy;
  double weight = 1.0;            ///< W > 0: weight of the energy against the data term
  std::vector<char> keep;         ///< per vertex: fixed to its start position (empty: none)
  /// Polar structures whose limit rows in the data term are BP's (as InterpolationOptions).
  std::vector<PolarStructure> polar;
};

struct FairResult {
  std::vector<Point3> positions;  ///< kept vertices copied bit for bit from `start`
  double energy_before = 0, energy_after = 0;
  double data_after = 0;          ///< sum |L P - c|^2
  FieldStats residual;            ///< |(L P)_v - c_v| over the vertices with a limit surface
  FieldStats displacement;        ///< |P_v - start_v|
  int kept = 0, free = 0;
};

/// Minimises  sum_v |(L P)_v - c_v|^2 + W E(P)  over the free vertices (L: limit_rows of the
/// level, with options.polar), the kept ones fixed at `start`. With c = the limit points
/// of `start` this smooths a surface while keeping it close to where it was (`fair`); with c =
/// the cage's own vertices it is interpolation regularised by the energy (`--fair W`).
/// energy_before is E(start). \throw std::invalid_argument (W <= 0, sizes), FitError (the
/// system could not be solved)
FairResult fair(const SubdivLevel& level, const std::vector<Point3>& start, const std::vector<Point3>& targets,
                const FairOptions& options);

/// The discrete thin-plate energy of an nu x nv grid of values (index i + nu j), as in
/// Weimer-Warren's thin-plate subdivision: D_uu^T D_uu + 2 D_uv^T D_uv + D_vv^T D_vv with the
/// second differences (1, -2, 1) in u and v wherever the three points exist and the cross
/// difference (1, -1, -1, 1) on every cell. Its rows are the grid masks (docs/fitting.md).
Eigen::SparseMatrix<double> grid_thin_plate_matrix(int nu, int nv);

}  // namespace subd2nurbs
