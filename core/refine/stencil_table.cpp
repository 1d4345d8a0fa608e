#include "core/refine/stencil_table.h"

namespace subd2nurbs {

double StencilTable::row_sum(int r) const {
  double s = 0;
  for (int k = offsets[r]; k < offsets[r + 1]; ++k) s += weights[k];
  return s;
}

void StencilTable::apply(const std::vector<Point3>& src, std::vector<Point3>& dst) const {
  const int rows = num_rows();
  dst.resize(rows);
  for (int r = 0; r < rows; ++r) {
    double x = 0, y = 0, z = 0;
    for (int k = offsets[r]; k < offsets[r + 1]; ++k) {
      const Point3& p = src[indices[k]];
      const double w = weights[k];
      x += w * p[0];
      y += w * p[1];
      z += w * p[2];
    }
    dst[r] = {x, y, z};
  }
}

StencilTable StencilTable::compose(const StencilTable& inner) const {
  StencilTable out;
  out.num_sources = inner.num_sources;
  out.offsets.reserve(offsets.size());
  // Dense accumulator over inner's sources, with a list of touched slots to reset.
  std::vector<double> acc(inner.num_sources, 0.0);
  std::vector<char> used(inner.num_sources, 0);
  std::vector<int> touched;
  for (int r = 0; r < num_rows(); ++r) {
    touched.clear();
    for (int k = offsets[r]; k < offsets[r + 1]; ++k) {
      const int mid = indices[k];
      const double w = weights[k];
      for (int j = inner.offsets[mid]; j < inner.offsets[mid + 1]; ++j) {
        const int s = inner.indices[j];
        if (!used[s]) {
          used[s] = 1;
          touched.push_back(s);
        }
        acc[s] += w * inner.weights[j];
      }
    }
    for (int s : touched) {
      out.indices.push_back(s);
      out.weights.push_back(acc[s]);
      acc[s] = 0.0;
      used[s] = 0;
    }
    out.offsets.push_back(static_cast<int>(out.indices.size()));
  }
  return out;
}

}  // namespace subd2nurbs
