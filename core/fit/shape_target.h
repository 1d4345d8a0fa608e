// A target shape for fit_to_shape (shape_fit.h) and the deviation measure
// (core/eval/target_distance.h): a triangle mesh, or a point cloud (points without triangles),
// with closest-point queries. Built once; queries are const and thread-safe.
//
// Closest points come from a bounding-volume hierarchy (ClosestPointTree) over the triangles or
// the points: boxes split at the median of the longest axis of the primitives' centres, leaves
// of at most 4 primitives, queries by branch and bound (nearer child first, subtrees whose box
// is farther than the best distance so far skipped). The result is exact (not approximate).
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "core/util/point3.h"

namespace subd2nurbs {

/// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5).
Point3 closest_point_on_triangle(const Point3& p, const Point3& a, const Point3& b, const Point3& c);

/// Barycentric weights of p (a point of the triangle's plane) in triangle (a, b, c); (1, 0, 0)
/// for a degenerate triangle.
std::array<double, 3> barycentric(const Point3& p, const Point3& a, const Point3& b, const Point3& c);

/// Exact closest-primitive queries over points or triangles.
class ClosestPointTree {
 public:
  ClosestPointTree() = default;
  /// Over points (triangles empty) or over the triangles (indices into points).
  ClosestPointTree(const std::vector<Point3>& points, const std::vector<std::array<int, 3>>& triangles);

  struct Hit {
    Point3 point{};        ///< the closest point
    double distance2 = 0;  ///< its squared distance to the query
    int element = -1;      ///< the point's or the triangle's index; -1 if the tree is empty
  };
  /// `hint`: a primitive likely near the answer (e.g. the previous answer for a query that moved
  /// a little): its distance bounds the search from the start, so that far branches are skipped.
  /// The answer is the closest primitive either way (among equally close ones, a hint may be
  /// returned where the search without it would return another).
  Hit closest(const Point3& q, int hint = -1) const;
  /// The closest among the primitives e with accept(e) (element -1 if none).
  Hit closest_if(const Point3& q, const std::function<bool(int)>& accept) const;
  bool empty() const { return nodes_.empty(); }

 private:
  struct Node {
    Point3 lo, hi;
    int first = 0, count = 0;  ///< leaf: primitives order_[first, first + count)
    int left = -1, right = -1;
  };
  int build(int first, int count, const std::vector<Point3>& centre);
  Point3 primitive_point(const Point3& q, int e) const;
  template <class Accept>
  void search(const Point3& q, const Accept& accept, Hit& best) const;
  std::vector<Point3> pts_;
  std::vector<std::array<int, 3>> tris_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
  std::vector<std::array<Point3, 2>> prim_box_;
};

/// The target: points, optional triangles, optional unit normals per point.
class ShapeTarget {
 public:
  /// `points`: the mesh's vertices or the cloud. `triangles`: indices into points (empty: a
  /// point cloud). `normals`: one unit normal per point (optional; a triangle target uses its
  /// own: area-weighted vertex normals, interpolated linearly over each triangle, so that the
  /// normal is continuous across edges and vertices). `triangle_samples` (triangle targets only): extra data points
  /// per triangle for the target -> surface term of a coarse mesh: 0 none, 1 the centroid,
  /// 3 the centroid and the midpoints of the centroid-vertex segments. \throw
  /// std::invalid_argument (empty, sizes, indices out of range)
  ShapeTarget(std::vector<Point3> points, std::vector<std::array<int, 3>> triangles = {},
              std::vector<Point3> normals = {}, int triangle_samples = 0);

  const std::vector<Point3>& points() const { return points_; }
  const std::vector<std::array<int, 3>>& triangles() const { return triangles_; }
  bool has_triangles() const { return !triangles_.empty(); }
  /// Whether closest() returns normals (triangles, or a cloud given with normals).
  bool has_normals() const { return has_triangles() || !normals_.empty(); }
  /// The points whose distance to the surface the target -> surface term measures: the points,
  /// then the triangle samples.
  const std::vector<Point3>& data_points() const { return data_points_; }
  /// Bounding-box diagonal of the points (the scale of every relative tolerance).
  double diagonal() const { return diagonal_; }

  struct Closest {
    Point3 point{};
    Point3 normal{};        ///< unit normal there (zero if !has_normals(); see the constructor)
    double distance = 0;
    int element = -1;       ///< triangle index, or point index for a cloud
  };
  /// `hint`: an element near the answer (ClosestPointTree::closest), e.g. the previous answer.
  Closest closest(const Point3& q, int hint = -1) const;

 private:
  std::vector<Point3> points_;
  std::vector<std::array<int, 3>> triangles_;
  std::vector<Point3> normals_;       ///< per point (unit; triangles: area-weighted vertex normals)
  std::vector<Point3> data_points_;
  double diagonal_ = 0;
  ClosestPointTree tree_;
};

}  // namespace subd2nurbs
