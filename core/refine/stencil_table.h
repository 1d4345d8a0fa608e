// StencilTable: a sparse linear map from source points to target points, one row per
// target (CSR). Refinement and limit evaluation are expressed as stencil tables, so that
// topology work is done once and positions are applied last.
#pragma once

#include <vector>

#include "core/util/default_init_vector.h"
#include "core/util/point3.h"

namespace subd2nurbs {

struct StencilTable {
  int num_sources = 0;
  DefaultInitVector<int> offsets{0};   ///< row r occupies [offsets[r], offsets[r+1])
  DefaultInitVector<int> indices;      ///< source index of each entry
  DefaultInitVector<double> weights;   ///< weight of each entry

  int num_rows() const { return static_cast<int>(offsets.size()) - 1; }
  int row_size(int r) const { return offsets[r + 1] - offsets[r]; }
  double row_sum(int r) const;

  /// dst[r] = sum_k weights[k] * src[indices[k]] over row r. dst is resized.
  void apply(const std::vector<Point3>& src, std::vector<Point3>& dst) const;

  /// The table of (this after inner): rows over inner's sources. Used to express a
  /// level-k point directly over the base vertices.
  StencilTable compose(const StencilTable& inner) const;
};

}  // namespace subd2nurbs
