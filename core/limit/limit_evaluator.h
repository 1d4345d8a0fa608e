// Exact evaluation of the Catmull-Clark limit surface at (face, u, v) (docs/math.md 9).
//
// Parameters follow OpenSubdiv's ptex convention: a quad is one ptex face with (0,0) at its
// first vertex and u running along its first edge; an n-gon (n != 4) is split into n sub-faces,
// one per corner, numbered consecutively (Far::PtexIndices). Sub-face s of an n-gon is the
// level-1 quad at corner s (core/refine/refiner.h layout): (0,0) at the corner vertex, u towards
// the midpoint of the corner's outgoing edge, v towards the midpoint of its incoming edge.
//
// Method, per query, on the face that contains the point at the current level:
//  1. the face is a regular patch (all corners smooth valence-4 interior vertices, or on
//     infinitely sharp creases / boundaries with two faces on the face's side, or corners with
//     one): bicubic B-spline of its 16 points, phantom points across sharp sides (docs/math.md 6.2);
//  2. the face has one interior smooth extraordinary vertex (all-quad 1-ring, no sharp edge)
//     and its other three corners are regular: Stam's eigenbasis evaluation (stam_eigen.h);
//  2'. the face's 4x4 grid is regular but crossed by semi-sharp crease lines in one direction,
//     one sharpness per line: B-spline along the lines times the closed-form semi-sharp curve
//     scheme across them (docs/math.md 9.7), as OpenSubdiv's single-crease patches;
//  3. otherwise (boundaries or creases at irregular vertices, darts, semi-sharp tags, n-gons,
//     two irregular corners): the face's 2-ring is cut out, refined once with refine_once
//     (identical to OpenSubdiv), and the query continues on the child face that contains it.
// Documented fallback: a point exactly at a corner where case 3 never ends (a boundary or crease
// vertex of irregular valence, a dart, a smooth corner, an interior valence-2 vertex) gets its
// exact limit position from limit_stencils, and derivatives / curvature from the point 2^-20
// inside the face along its diagonal; `exact_derivatives` is false there. At an interior
// extraordinary vertex itself ((0,0) of case 2) the position and normal are exact (limit masks,
// docs/math.md 2.2), the parametric derivatives are the edge-ray limit tangents scaled by 1/(3n)
// (which is exact for n = 4), and curvatures are NaN (the parametrization is singular there).
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "core/nurbs/nurbs_eval.h"
#include "core/refine/refiner.h"

namespace subd2nurbs {

struct LimitSample {
  Point3 p{}, du{}, dv{};           ///< position, first derivatives w.r.t. the ptex (u, v)
  Point3 duu{}, duv{}, dvv{};       ///< second derivatives
  Point3 normal{};                  ///< unit normal du x dv (outward for a counter-clockwise cage)
  /// Principal curvatures k1 >= k2, mean H = (k1 + k2) / 2 and Gaussian K = k1 k2, signed with
  /// respect to `normal`: a sphere with outward normal has k = -1/R (docs/math.md 9.6).
  double k1 = 0, k2 = 0, mean = 0, gauss = 0;
  bool exact_derivatives = true;    ///< false at the documented fallback points
};

/// Position and first derivatives only (what OpenSubdiv's patch evaluation returns).
struct LimitPoint {
  Point3 p{}, du{}, dv{};
};

/// How evaluate() found a point: Regular, Stam or SemiSharp in the query's own face (closed form),
/// Refined after refining towards it, Fallback at the documented corner points.
enum class LimitMethod : unsigned char { Regular, Stam, Refined, Fallback, SemiSharp };

class LimitEvaluator {
 public:
  /// `base` must outlive nothing: it is copied. positions: one per base vertex.
  LimitEvaluator(SubdivLevel base, std::vector<Point3> positions);
  ~LimitEvaluator();
  LimitEvaluator(LimitEvaluator&&) noexcept;

  int num_ptex_faces() const { return static_cast<int>(ptex_face_.size()); }
  /// First ptex index of base face f (n ptex faces for an n-gon).
  int first_ptex(int f) const { return face_ptex_[f]; }
  /// Base face of a ptex face.
  int ptex_to_face(int ptex) const { return ptex_face_[ptex]; }
  const SubdivLevel& base() const { return base_; }
  const std::vector<Point3>& positions() const { return positions_; }

  /// Evaluation at a ptex face. \throw std::out_of_range for a bad ptex index or (u, v)
  /// outside [0,1]^2, std::domain_error on a hole (no limit surface).
  LimitSample evaluate_ptex(int ptex, double u, double v, LimitMethod* method = nullptr) const;
  /// Quad face f (sub = 0) or sub-face `sub` of n-gon f.
  LimitSample evaluate(int face, int sub, double u, double v, LimitMethod* method = nullptr) const;
  /// The same values of p, du, dv as evaluate(), without second derivatives and curvature
  /// (faster on regular faces).
  LimitPoint evaluate_point(int face, int sub, double u, double v) const;
  /// evaluate() on the tensor grid us x vs of one (sub-)face: out[a * nv + b] at (us[a], vs[b]),
  /// the same values up to rounding. On a face of case 1 or 2' the bicubic sum is contracted
  /// along u once per us[a]; elsewhere the points are evaluated one by one.
  void evaluate_grid(int face, int sub, const double* us, int nu, const double* vs, int nv, LimitSample* out) const;
  /// True where the limit over the whole (sub-)face is one bicubic polynomial of (u, v): a
  /// quad of case 1 (a regular patch). False elsewhere, also where it may be one after all.
  bool is_polynomial(int face, int sub) const;

 private:
  struct FaceCache;
  SubdivLevel base_;
  std::vector<Point3> positions_;
  std::vector<int> face_ptex_;   ///< base face -> first ptex
  std::vector<int> ptex_face_;   ///< ptex -> base face
  std::vector<int> face_cache_;  ///< base face -> index into cache_ or -1
  std::vector<FaceCache> cache_;

 public:
  struct DescentCache;  ///< refined neighbourhoods shared by nearby queries (limit_evaluator.cpp)

 private:
  std::unique_ptr<DescentCache> descent_;
};

/// Principal curvatures etc. from derivatives (fills normal, k1, k2, mean, gauss).
void finish_sample(LimitSample& s);

/// A sample of any surface from its derivatives (e.g. a patch's, core/nurbs/nurbs_eval.h),
/// finished with finish_sample.
LimitSample sample_from_derivatives(const SurfaceDerivs& d);

}  // namespace subd2nurbs
