// The mesh path (issue #28): a dense triangle mesh is a shape to reproduce, not a cage. Every
// front end (`subd2nurbs convert` and `info`, the Python module, the FreeCAD workbench) loads a
// file through load_source, which decides the road by the rule below; a mesh then becomes a cage
// by mesh_to_cage: sharp features (core/features), a field-aligned all-quad cage with the
// features as infinitely sharp creases (core/remesh), the cage's limit surface fitted to the mesh
// (core/fit/shape_fit.h). From there the conversion is the cage path's.
//
// The rule (docs/meshes.md "Which path"), in order:
//  1. `input` mesh or cage (the setting) decides;
//  2. a file with faces that are not triangles (quads, n-gons) is a cage;
//  3. a file with crease, corner or hole tags is a cage;
//  4. a file of triangles only whose triangles all pair back into quads (quad recovery,
//     core/mesh/quad_recovery.h; triangles around a polar fan vertex may stay) is a
//     triangulated cage;
//  5. otherwise an STL, PLY, OFF or glTF file is a mesh, and so are at least kMinMeshTriangles
//     triangles from anywhere else (OBJ, the Python module's arrays, a FreeCAD Mesh); fewer are
//     a triangle cage.
#pragma once

#include <algorithm>
#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "converter/pipeline/input.h"
#include "converter/pipeline/shape_fit_report.h"
#include "core/fit/planar_regions.h"
#include "core/remesh/quad_remesh.h"

namespace subd2nurbs::pipeline {

/// Which road a file takes: decided by the rule (Auto), or as the user says.
enum class InputKind { Auto, Mesh, Cage };
const char* to_string(InputKind kind);  ///< "auto", "mesh", "cage"
/// \throw SettingsError ("input")
InputKind input_kind(const std::string& name);

/// Triangles from other than an STL, PLY, OFF or glTF file take the mesh path from this many (rule 5).
constexpr int kMinMeshTriangles = 200;

/// The mesh path's settings (the settings table's rows "input", "target_faces", "aim_at_target",
/// "edge_length", "exact_spacing", "fit_tolerance", "feature_angle").
struct MeshPathSettings {
  InputKind input = InputKind::Auto;
  int target_faces = 0;        ///< quads of the cage wanted; 0 with edge_length 0: automatic
  /// With target_faces: rerun the remesh at corrected spacings until the cage has 0.9 .. 1.0 x
  /// target_faces quads (at most 5 runs; a feature floor may keep it above: docs/remesh.md step 7);
  /// otherwise target_faces is approximate (often 10 .. 30 % over). Ignored without target_faces.
  bool aim_at_target = false;
  double edge_length = 0;      ///< the cage's edge length in model units (used when target_faces is 0)
  /// With edge_length: one extraction at exactly that spacing, no second run at a coarser one
  /// when the faces exceed area / edge_length^2 by 30 % (QuadRemeshOptions::exact_spacing).
  bool exact_spacing = false;
  /// With the automatic size: the two-sided max distance between the fitted limit surface and
  /// the mesh to reach, relative to the bounding-box diagonal; the cage is remeshed at a size
  /// predicted from the measured distance until it is met (the size rule below); 0: off (one
  /// remesh at the automatic size).
  double fit_tolerance = 1e-3;
  double feature_angle = 30;   ///< degrees: an edge between faces whose normals differ more is sharp
};

/// The size rule (docs/meshes.md "Size chosen by the fit tolerance"). With the automatic size and
/// a fit tolerance, the mesh is remeshed and fitted at most kMaxSizeRounds times. The model:
/// the two-sided max distance d falls as h^2 (h the cage's edge length), so d x quads is about a
/// constant C (measured on fandisk over 464 .. 1374 quads: d ~ h^2.26, each size within a factor
/// 0.62 .. 1.49 of that trend). After a round that misses the tolerance, the next size is C /
/// (kSizeMargin x tolerance), C the geometric mean of d x quads over the rounds so far: the margin
/// covers that scatter, so one more round usually meets it. After a first round within
/// kCoarsenBelow x the tolerance, one coarser round at the same prediction. The sizes stay within
/// kMaxSizeFactor of the first round's target (time and memory grow with the quads): a prediction
/// beyond it ends the rounds (the tolerance is then not met; the warning names the predicted
/// size), one below it is raised to it. The kept round: the fewest quads among those that meet
/// the tolerance, else the closest.
constexpr int kMaxSizeRounds = 3;
constexpr double kSizeMargin = 0.7;
constexpr double kCoarsenBelow = 0.5;
constexpr double kMaxSizeFactor = 2.5;

/// The automatic size: this many quads per unit of the mesh's area / diagonal^2, within limits.
int automatic_target_faces(const MeshInput& mesh);

/// Which road, and why in one sentence ("its 12946 triangles do not pair back into quads (330
/// stay triangles): a mesh to reproduce").
struct InputRoute {
  bool mesh = false;
  std::string reason;
};

/// What load_source read: on the cage road the cage as load_input gives it; on the mesh road the
/// mesh's triangles (as in the file, not paired into quads) and the file's warnings.
struct LoadedSource {
  InputRoute route;
  std::optional<LoadedInput> cage;  ///< the cage road
  LoadedCage mesh;                  ///< the mesh road: the file's faces (not paired into quads)
  std::vector<std::string> warnings;  ///< the mesh road's reading warnings ("FILE:LINE: warning: ...")
};

/// Reads `path` and decides its road by the rule (file comment).
/// \throw InputError (unreadable or invalid file), SettingsError
LoadedSource load_source(const std::string& path, InputKind requested, const UsdReadOptions& usd = {});

/// Decides the road of a cage already read (rule 2 .. 5). `path` gives the format (by extension).
InputRoute route_input(const LoadedCage& read, const std::string& path, InputKind requested);

/// The normal angle across a kept feature curve of the fitted surface against the mesh's
/// dihedral angle there (both in degrees, as the angle between the two sides' normals).
struct FeatureAngleStats {
  int samples = 0;            ///< points measured (3 per feature edge of the cage, where a mesh feature edge runs along)
  double max_difference = 0;  ///< max |surface angle - mesh angle|, degrees
  double mean_difference = 0;
  int where_edge = -1;        ///< the worst cage feature edge (an edge number of the fitted cage's PolyMesh)
  Point3 where{};             ///< the worst sample's point on the surface
};

/// A feature curve whose normal angle differs from the mesh's dihedral by more than this
/// (degrees) is folded, not merely off (docs/meshes.md "Folded creases"): the mesh path warns.
/// Unfolded curves stay within ~10 degrees (fandisk at 500 .. 1600 target faces: up to 9.7;
/// folded: 22 .. 140).
constexpr double kFoldedCreaseDegrees = 20;

/// One remesh and fit of the size rule.
struct MeshPathRound {
  int target_faces = 0;   ///< asked of the remesher (0 with edge_length)
  int quads = 0;          ///< made (0: the round failed, `failure` says why)
  double to_mesh = 0, from_mesh = 0;  ///< fit.after's max limit_to_target, target_to_limit (of the diagonal)
  double ms = 0;          ///< its remesh, fit and measure
  double remesh_ms = 0;   ///< its remesh alone
  std::string failure;    ///< a later round's remesh or fit error (the rounds end, the best so far is kept)
  double distance() const { return std::max(to_mesh, from_mesh); }
};

/// What the mesh path did, for the report and the summaries.
struct MeshPathReport {
  InputRoute route;
  int input_vertices = 0, input_triangles = 0;
  QuadRemeshStats remesh;
  int feature_edges_in = 0, corners_in = 0, feature_chains_in = 0;
  int faded_edges_in = 0;  ///< of feature_edges_in, edges below the feature angle that continue a fading crease
  int fading_ends_in = 0;  ///< where fading creases vanish (darts in the cage; not in corners_in)
  int plane_edges_in = 0;  ///< of feature_edges_in, edges below the feature angle where a planar region ends on a narrow fillet
  int target_faces = 0;         ///< asked for (after the automatic choice), 0 if edge_length
  double edge_length = 0;       ///< asked for, model units (0 if target_faces)
  double feature_angle = 30;
  ShapeFitOptions fit_options;
  ShapeFitRun fit;              ///< the fit, with the two-sided distance before and after
  FeatureAngleStats feature_angles;
  FlattenStats planar;          ///< the planar regions made exactly planar (core/fit/planar_regions.h)
  /// The size rule: "given" (target_faces or edge_length), "automatic" (fit_tolerance 0) or
  /// "fit_tolerance"; the rounds tried, in order, and the one kept (the numbers above are its).
  std::string size_rule = "given";
  double fit_tolerance = 0;
  std::vector<MeshPathRound> rounds;
  int kept_round = 0;
  bool tolerance_met = true;    ///< the kept round meets fit_tolerance (true when there is none)
  int predicted_target_faces = 0;  ///< the rounds ended at a prediction beyond kMaxSizeFactor: that size, else 0
  /// "subd2nurbs: warning: ..." lines: the fit tolerance not met; a folded feature curve
  /// (kFoldedCreaseDegrees).
  std::vector<std::string> warnings;
  double remesh_ms = 0, fit_ms = 0, measure_ms = 0;  ///< over all rounds
};

/// The cage made from a mesh, fitted, ready for convert().
struct MeshCage {
  LoadedInput cage;                ///< the cage (tags: feature creases and corners), validated
  std::vector<Point3> positions;   ///< the fitted positions
  /// Cage edges tagged to split concave corner sectors (core/remesh/quad_remesh.h): creases of
  /// the cage, not features of the mesh.
  std::vector<std::array<int, 2>> sector_edges;
  MeshPathReport report;
};

/// Progress of the mesh path: a stage line ("detecting features", "remeshing", "fitting"),
/// and a fraction of the remesh; returning false from either cancels (Error, kind Usage,
/// "cancelled").
struct MeshPathProgress {
  std::function<void(const std::string& text)> stage;
  std::function<bool(double fraction)> fraction;
};

/// The mesh's features, an all-quad cage of it, and the cage fitted to it (see the file comment);
/// with the automatic size and a fit tolerance, at the size the size rule chooses (above).
/// Polygons are fan-triangulated first; infinitely sharp crease tags (an OBJ's `t crease` with
/// sharpness >= 10 given with --input mesh) are features the user tagged, kept whatever their
/// angle; other tags are ignored.
/// \throw SettingsError (settings), Error (remesh or fit impossible, cancelled)
MeshCage mesh_to_cage(const LoadedCage& mesh, const MeshPathSettings& settings, const MeshPathProgress& progress = {});

/// The rules of the mesh settings: target_faces >= 0, edge_length >= 0, fit_tolerance in [0, 1),
/// feature angle in (0, 180).
/// \throw SettingsError
void validate(const MeshPathSettings& settings);

/// The mesh path's member of the conversion report ("mesh": docs/formats.md).
void write_mesh_path(JsonWriter& w, const MeshPathReport& report);

/// A few lines for stderr: the cage, the features, the fit's distances, the size rule's rounds.
std::string mesh_path_summary(const MeshPathReport& report);

}  // namespace subd2nurbs::pipeline
