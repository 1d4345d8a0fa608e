// Fitting a cage's exact Catmull-Clark limit surface to a target shape (issue #27;
// docs/fitting.md "Fitting to a shape", docs/math.md 14).
//
// The cage's topology and tags are kept; its vertex positions P are solved so that the limit
// surface fits the target (a triangle mesh or a point cloud, shape_target.h) in least squares,
// regularised by the thin-plate energy (fairing.h):
//
//   F(P) = (1/Na) sum_i |W_i^1/2 (S_i P - c_i)|^2 + (w_b/Nb) sum_j |V_j^1/2 (R_j P - t_j)|^2
//        + smoothing * E_tp(P) / N_ptex
//
//  * S_i: exact limit rows (over the cage) of the limit points of the level-k vertices (the cage
//    refined `levels` times): linear in P, no approximation (shape_fit_sample_rows).
//  * surface -> target: c_i the closest target point of sample i; point-to-plane (W_i = n n^T,
//    n the target's normal at c_i) in the first phase, point-to-point (W_i = I) in the second.
//  * target -> surface: every data point t_j of the target paired with its closest surface point,
//    found from the nearest sample: on the regular level-k patches around it (bicubic B-splines
//    of 16 level-k points) by Gauss-Newton in the patch's (u, v), exactly; on the other level-k
//    faces (within 2^-k of extraordinary vertices, creases, boundaries) on the two triangles of
//    their corners' limit points. R_j is that point's row (B-spline weights times the level-k
//    rows, or barycentric weights times three sample rows); V_j = m m^T (m the surface normal
//    there) when t_j - foot is along m, else I (t_j beyond the surface's border).
//  * the pairings are recomputed between solves (closest-point iterations, ICP).
// Each solve is one sparse symmetric system in the 3n coordinates (the point-to-plane terms
// couple x, y, z; 3n is small, so the coupled system is solved rather than alternating), with a
// small proximal term mu |P - P_prev|^2 that vanishes at convergence. All terms scale with the
// square of the model size and are invariant under translation, so the result is scale- and
// translation-invariant (tested to 1e-15). Tags (boundaries, creases, corners, holes) are
// respected because the rows come from the tagged cage; polar structures are ignored
// (Catmull-Clark rows everywhere).
//
// Cost per iteration: closest-point queries (BVH started from the previous iteration's answer,
// parallel_for), then the normal equations: the samples' rows as one small dense product per
// cage face (faces in parallel, summed in face order: results independent of the thread count),
// the data points' rows one by one, into 3 x 3 blocks per cage vertex pair that shares a face's
// support; then a sparse LDLT whose ordering and symbolic analysis are done once per fit.
#pragma once

#include <functional>
#include <vector>

#include "core/fit/shape_target.h"
#include "core/refine/refiner.h"

namespace subd2nurbs {

struct ShapeFitOptions {
  int levels = 3;               ///< refinement levels of the samples (level-k vertex limits); 1..5
  double smoothing = 1e-4;      ///< weight of the thin-plate energy per ptex face (dimensionless)
  int max_iterations = 30;      ///< closest-point iterations (each: pair, then solve)
  /// Stop when the RMS of both distance terms (surface -> target point-to-point, target ->
  /// surface as measured by the solver) is at most tolerance x target diagonal.
  double tolerance = 1e-7;
  /// Stop when the objective falls by less than this fraction in an iteration of the last phase.
  double min_improvement = 1e-6;
  /// Stop (in the point-to-plane phase: go on to point-to-point) when the measured two-sided RMS
  /// distance (sqrt of the mean of the two terms' squared RMS) falls by less than this fraction
  /// in an iteration: the fit has stopped improving the distance at a rate worth an iteration.
  /// 0: off (only min_improvement, the tolerance and the iteration cap stop).
  double min_gain = 0.02;
  /// Point-to-plane iterations at most, before point-to-point (also switched as soon as the
  /// objective falls by less than plane_switch in one iteration). 0: point-to-point throughout.
  /// Ignored (0) for a point cloud without normals.
  int plane_iterations = 50;
  double plane_switch = 0.01;
  /// Weight of the target -> surface term (surface -> target: 1). The target's points are exact
  /// (a triangle mesh's vertices lie on the shape), its triangles are chords that sag between
  /// them, so the target -> surface term leads (docs/fitting.md "Recovery").
  double target_weight = 1.0;
  /// Relative weight of the proximal term |P - P_prev|^2 (times the mean diagonal of the data
  /// normal matrix); keeps each solve regular where the data leave a direction free.
  double proximal = 1e-8;
  /// Weight of the surface -> target term in the point-to-point phase, relative to the first
  /// phase: the chords' sag would hold a fit that slid along the surface; the term keeps only
  /// the surface from floating where the target has no points. In (0, 1]. An exact target
  /// wants 1e-3 (docs/fitting.md); 1 keeps the surface on a target it cannot reach.
  double final_surface_weight = 1.0;
  /// Crease curves follow the target's sharp edges: the target's feature vertices (interior
  /// edges whose faces' normals differ by more than crease_angle degrees; 0: off) are fitted to
  /// the nearest crease curve of the surface (level-k edges still sharp at level k) when it is
  /// within crease_reach x the mean length of the level-k crease edges.
  double crease_angle = 0.0;
  double crease_reach = 4.0;
  /// The surface's normal on each side of the crease curves held at the target's (0: off), in
  /// the cage faces at a corner (a vertex tagged infinitely sharp). At the middle of every
  /// level-k crease edge there, on each side, the normal T x D of the limit (T
  /// along the crease, D across it along the level-k edge leaving it) is compared with the
  /// target's normal n there (the normal of the target's triangle closest to the surface point
  /// half a level-k edge inside, used when it faces within crease_normal_guard degrees of the
  /// surface's normal there): to first order the normal is off by (n.T) / |T| along the crease
  /// and by ((D.t) (n.T) / |T| - n.D) / (D.e) across it (t, e the unit vectors along T and
  /// across it in the target's plane), both linear in the positions with the frame frozen per
  /// iteration; each is scaled by |D| to a length and weighted by crease_normal_weight x one
  /// surface sample x min(1 / sin^2 a - 1, 10), a the angle between T and D; left out of the
  /// step control's objective (its rows change between iterations). So it acts where a quad
  /// meets a crease at an acute angle (a wedge between two crease curves meeting at a sharp
  /// corner, where the normal turns 1 / sin a times faster than D's tilt, which the positions
  /// alone do not see: fandisk's fan tip, a = 17 deg, 8 deg off; docs/meshes.md) and not where
  /// the quad meets the crease square (a = 90 deg: the positions hold the normal there).
  double crease_normal_weight = 0.0;
  double crease_normal_guard = 15.0;
  /// Cage vertices held on planes (the mesh path's planar regions, core/fit/planar_regions.h):
  /// each adds plane_weight x (the normal equations' mean diagonal) x (normal . P_vertex -
  /// offset)^2 to every solve, so that the rest of the cage fits around the held vertices.
  struct VertexPlane {
    int vertex = 0;
    Point3 normal{};  ///< unit
    double offset = 0;
  };
  std::vector<VertexPlane> vertex_planes;
  double plane_weight = 1e3;
};

/// The options for a target that lies on a subdivision surface (a dense sampling of an exact
/// limit, no noise): target -> surface weight 30, surface -> target 1e-3 in the last phase, the
/// crease term at 30 deg, smoothing 0, tolerance 1e-8, up to 100 iterations. They recover a
/// perturbed cage's surface to 1e-6 of the diagonal on the oracle shapes (docs/fitting.md); the
/// defaults keep weights 1 / 1 for targets a cage cannot reach (scans, CAD meshes).
ShapeFitOptions exact_target_options();

enum class ShapeFitStop : unsigned char {
  Tolerance,      ///< both RMS distances at most options.tolerance (relative)
  Converged,      ///< the objective improved by less than min_improvement, or the distance by less than min_gain
  IterationLimit, ///< max_iterations reached
  Cancelled,      ///< the progress callback returned false (positions: the last solved cage)
};
const char* to_string(ShapeFitStop s);

/// One closest-point iteration, measured at its start (its pairings, before its solve).
/// Distances relative to the target's diagonal.
struct ShapeFitIteration {
  double objective = 0;        ///< F / diagonal^2
  double surface_rms = 0, surface_max = 0;  ///< samples to their closest target points
  /// data points to their closest surface points (along the surface normal; the whole distance
  /// for a point beyond the surface's border)
  double target_rms = 0, target_max = 0;
  bool point_to_plane = false;              ///< the surface -> target term's phase
};

struct ShapeFitResult {
  std::vector<Point3> positions;             ///< the fitted cage (one per cage vertex)
  std::vector<ShapeFitIteration> history;    ///< one per iteration, plus the final state last
  ShapeFitStop stop = ShapeFitStop::IterationLimit;
  int iterations = 0;                        ///< solves done
  int samples = 0;                           ///< surface samples (level-k vertices with a limit)
  /// The final state (= history.back()): distances relative to the target's diagonal.
  double surface_rms = 0, surface_max = 0, target_rms = 0, target_max = 0;
};

/// Called after each pairing that a solve follows, with (iteration, objective / diagonal^2); return false
/// to cancel (the result is then the cage of the last solve, stop = Cancelled).
using ShapeFitProgress = std::function<bool(int iteration, double objective)>;

/// The solver's surface samples: the exact limit rows, over the cage's vertices, of the limit
/// points of the vertices of the cage refined `levels` times (those with a limit surface, in
/// level-k vertex order). Row r applied to the cage positions is a point of the limit surface.
StencilTable shape_fit_sample_rows(const SubdivLevel& cage, int levels);

/// A similarity x -> scale R x + t (R a rotation).
struct Similarity {
  double scale = 1;
  double R[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Point3 t{0, 0, 0};
  double rms = 0;  ///< RMS distance of the mapped points to the target, relative to its diagonal
  Point3 apply(const Point3& p) const {
    Point3 q;
    for (int i = 0; i < 3; ++i) q[i] = scale * (R[i][0] * p[0] + R[i][1] * p[1] + R[i][2] * p[2]) + t[i];
    return q;
  }
};

/// The similarity that best maps `points` (e.g. a cage's limit points) onto `target`: the 24
/// axis-aligned rotations with the bounding boxes' centres and diagonals matched are tried, the
/// one with the smallest RMS closest-point distance (of at most about 2 048 of the points, evenly
/// strided) refined by closest-point iterations (all points) with Umeyama's closed-form
/// similarity (`iterations` at most). For a shape given in another frame, scale or orientation
/// (rotated by multiples of 90 degrees about the axes, or near them).
Similarity register_to_target(const std::vector<Point3>& points, const ShapeTarget& target, int iterations = 200);

/// The cage edges that lie along the target's sharp features, to be tagged infinitely sharp
/// before a fit (`subd2nurbs fit --tag-features`): an untagged cage's limit rounds a part's
/// sharp edges off, a tagged one can make them. The target's feature edges (detect_features:
/// interior edges whose faces' normals differ by more than `angle_degrees`) are split into
/// feature curves at their corners; an interior cage edge that is not infinitely sharp yet is
/// listed when both its ends and its midpoint (the cage's own `positions`, not its limit: for a
/// cage drawn on the shape, e.g. a remesh) lie within `reach` x the shortest cage edge at either
/// end of one same curve. Sorted edge indices; none for a point cloud or a target that is not
/// manifold.
std::vector<int> feature_edges_on_target(const SubdivLevel& cage, const std::vector<Point3>& positions,
                                         const ShapeTarget& target, double angle_degrees = 30.0, double reach = 0.25);

/// Fits the limit surface of `cage` (topology and tags; positions ignored) starting from the
/// positions `start` to `target`. \throw std::invalid_argument (sizes, options), FitError
/// (interpolate.h: a system could not be factorised)
ShapeFitResult fit_to_shape(const SubdivLevel& cage, const std::vector<Point3>& start, const ShapeTarget& target,
                            const ShapeFitOptions& options = {}, const ShapeFitProgress& progress = {});

}  // namespace subd2nurbs
