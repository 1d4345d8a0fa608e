// Limit interpolation: the cage whose exact limit surface passes through given points, one per
// cage vertex (docs/fitting.md). With the limit operator L (limit_rows.h) this is the sparse
// square system L P = c, solved per coordinate by sparse LU with the residual checked.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "core/fit/limit_rows.h"
#include "core/util/error.h"

namespace subd2nurbs {

/// The system cannot be solved reliably. `vertices` are the ones it is about (for a singular
/// or badly conditioned system: where the near-null vector of L is largest).
class FitError : public Error {
 public:
  FitError(const std::string& message, std::vector<int> vertices)
      : Error(ErrorKind::Fit, message), vertices_(std::move(vertices)) {}
  const std::vector<int>& vertices() const { return vertices_; }

 private:
  std::vector<int> vertices_;
};

/// Size of a residual or displacement field: max (and where), mean, over the vertices with a
/// limit surface.
struct FieldStats {
  double max = 0, mean = 0;
  int where = -1;
};
FieldStats field_stats(const std::vector<Point3>& a, const std::vector<Point3>& b,
                       const std::vector<char>* skip = nullptr);

struct InterpolationOptions {
  /// Polar structures whose pole and rings 1, 2 interpolate with the BP limit (the surface the
  /// converter's polar caps stand for); empty: Catmull-Clark everywhere.
  std::vector<PolarStructure> polar;
  /// Largest acceptable estimate of the condition number of L.
  double max_condition = 1e12;
};

struct InterpolationResult {
  std::vector<Point3> positions;   ///< the solved cage
  FieldStats residual;             ///< |L P - c| (model units)
  FieldStats displacement;         ///< |P - c|
  double condition = 0;            ///< estimate of cond_2(L) = sigma_max / sigma_min
  int polar_vertices = 0;          ///< rows from BP
  int local_rows = 0;              ///< rows from the local refinement of semi-sharp fans
  std::vector<int> no_surface;     ///< vertices without limit surface (kept at their target)
  /// L is singular or worse conditioned than max_condition, but the targets are in its range:
  /// the interpolating cage is not unique, and the one nearest to the targets (minimum-norm
  /// displacement) was chosen. `null_vertices`: where L's near-null vector is largest.
  bool singular = false;
  std::vector<int> null_vertices;
};

/// Solves L P = c for the cage P of `level` (whose topology and tags are kept) with targets
/// c = `targets`. A singular (or badly conditioned) L is accepted when some cage still
/// interpolates (see InterpolationResult::singular).
/// \throw FitError (no cage interpolates: singular or badly conditioned with the targets outside
///        its range; the message and vertices() name where), std::invalid_argument (sizes)
InterpolationResult interpolate(const SubdivLevel& level, const std::vector<Point3>& targets,
                                const InterpolationOptions& options = {});

}  // namespace subd2nurbs
