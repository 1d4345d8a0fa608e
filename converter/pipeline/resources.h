// Resource guards: what a conversion or a refinement will need, estimated from the cage
// before any heavy work, and the limits it is checked against. One place, so that the
// estimate can follow the patch builder (adaptive refinement will make it smaller).
// Used by the CLI, the Python module and (through it) the FreeCAD workbench.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "converter/pipeline/settings_error.h"
#include "core/refine/refiner.h"
#include "core/util/point3.h"
#include "core/util/error.h"

namespace subd2nurbs::pipeline {

/// Default limits. Convert / check: polynomial pieces the patch builder makes (one per regular
/// coarse quad, more at irregular vertices and along semi-sharp creases: catmark_rook makes
/// 428 000). Refine: output faces.
constexpr double kDefaultMaxConvertFaces = 4e6;
constexpr double kDefaultMaxRefineFaces = 2e7;

/// Peak memory of a conversion, per what it allocates (Release build, Debian 12, x86-64; fitted
/// on the 87 OpenSubdiv shapes, the real models and the costly cases of docs/hardening.md,
/// `scripts/measure_estimate.py`): the process itself (libraries, OCCT's and the readers'
/// tables), per polynomial piece of the patch builder (its Bezier net, the quadtree, the local
/// refinement), per regular coarse quad, per pole of the B-splines at irregular vertices beyond a
/// regular quad's 16, per valence of an irregular vertex's fan
/// piece (the 5 rings of its level-k piece, its nets and the deviation's local refinement),
/// and per exported face, B-rep edge and pole (OCCT's faces, curves and pcurves, the STEP
/// model's entities and text).
constexpr double kProcessBytes = 35e6;
constexpr double kBytesPerQuad = 3200;  ///< a regular quad: its piece, patch, 16 poles, packing
constexpr double kBytesPerPiece = 360;
constexpr double kBytesPerPatchPole = 670;
constexpr double kBytesPerFanValence = 20000;
/// A fan's piece holds the faces within 5 rings of its vertex at its level: the stars of the
/// irregular vertices next to it too. A valence-3 rim vertex beside a 1000-gon's centre holds
/// that centre's 1000 faces (and the deviation measures on them): per valence of the irregular
/// vertices that share a coarse face with the fan's vertex (fitted on the prism with 1000-gon
/// caps: 2000 rim fans, first build 1.9 GB where the rest of the model is 0.7 GB).
constexpr double kBytesPerNearbyValence = 600;
constexpr double kBytesPerFace = 49000;
constexpr double kBytesPerEdge = 14500;
constexpr double kBytesPerFacePole = 300;
/// Without the B-rep (patch JSON, check): the exported set and the JSON text.
constexpr double kBytesPerFacePoleNoBrep = 150;
constexpr double kRefineBytesPerFace = 450;

/// CPU time of a conversion to STEP (one core of this machine, idle; fitted as the bytes): the
/// start, per piece, per exported pole and face (the B-rep and the STEP writer), per valence and
/// level of a fan, per valence^2 and level at a fan of at most kSharedPieceValence faces (each
/// quad there refines its own piece holding the vertex's whole star at each level down to its
/// zone; above that valence the quads share one piece, core/patch/patch_builder.cpp, and the
/// per-valence term covers it), and per valence^2 of any fan for the self-intersection check
/// (core/eval/self_intersection.cpp): the n thin faces at a valence-n vertex are tessellated into
/// slivers whose boxes overlap those of the neighbouring faces' (a 1000-gon: about 10 s).
constexpr double kStartSeconds = 0.05;
constexpr double kSecondsPerPiece = 4e-6;
constexpr double kSecondsPerPole = 1e-5;
constexpr double kSecondsPerFace = 1e-3;
constexpr double kSecondsPerFanValenceLevel = 5e-5;
constexpr double kSecondsPerFanValence2Level = 1.4e-6;
constexpr double kSecondsPerFanValence2Intersections = 1e-5;
constexpr double kSecondsPerNearbyValence = 4e-6;  ///< per build of the fan's piece and its deviation
/// A polar cap of valence n: its distance to the Bezier-patch limit and curvatures, sampled
/// about n times over the cap's n sectors (a 1024-sided capsule's two caps: 2 s).
constexpr double kSecondsPerCapValence2 = 1e-6;
/// PatchOptions::shared_piece_valence's default (core/patch/patch_builder.h).
constexpr int kSharedPieceValence = 8;
/// Most extra levels a tolerance adds at one fan (each costs a few knots in the patches at that
/// vertex); a tolerance needing more is reported as capped. The estimate before any work
/// predicts a curved fan's levels up to it.
constexpr int kMaxFanExtraLevels = 12;

/// Most levels a uniform refinement takes: beyond the face limit for any cage, and 4^levels
/// stays far from overflowing.
constexpr int kMaxRefineLevels = 20;

/// What the user allows; not given: the default.
struct ResourceLimits {
  std::optional<double> max_faces;   ///< > 0; default kDefaultMaxConvertFaces or kDefaultMaxRefineFaces
  std::optional<double> max_memory;  ///< bytes, > 0; default default_max_memory()
  /// The threads one conversion's parallel loops use, 1 .. kMaxThreads; default: the machine's
  /// hardware threads (core/util/parallel.h ThreadLimit).
  std::optional<int> threads;
};

/// The most threads the `threads` setting takes.
constexpr int kMaxThreads = 1024;

/// The rules of the limits (max_faces, max_memory: positive numbers) and of a refinement's
/// levels (0 .. kMaxRefineLevels). \throw SettingsError
void validate(const ResourceLimits& limits);
void check_refine_levels(int levels);
/// A memory size as parse_memory_size reads it. \throw SettingsError ("max_memory")
double memory_size(const std::string& text);

/// 3/4 of the physical memory, or of the address-space / data-size limit (ulimit -v / -d)
/// when that is lower; at least 256 MiB.
double default_max_memory();

struct ResourceEstimate {
  double faces = 0;    ///< work units: convert: polynomial pieces; refine: output faces, exact
  double patches = 0;  ///< NURBS patches (convert), 0 for refine
  double poles = 0;    ///< their control points
  double exported_faces = 0;  ///< faces of the B-rep / patch JSON (convert)
  double exported_poles = 0;  ///< their control points
  double bytes = 0;    ///< peak memory (resident), within 2x of the measured peak (docs/hardening.md)
  double seconds = 0;  ///< CPU time of one core, roughly (a time class, time_class)
};

/// The order of magnitude of a time: "under a second", "seconds" (< 10 s), "tens of seconds"
/// (< 1 min), "minutes" (< 10 min), "ten minutes or more".
std::string time_class(double seconds);

/// One irregular vertex of the coarsest all-quad level as the estimate costs it: its valence,
/// the coarse quads at it and the levels its fan goes below the coarse level (2 + extra).
struct FanCost {
  int valence = 0;
  int corners = 0;
  int levels = 2;
  int nearby = 0;  ///< the valences of the irregular vertices sharing a coarse face with it, summed
  bool curved = true;  ///< its star is not flat (known before any work only with positions)
};

/// FanCost::nearby of the fan at vertex v of mesh m: the valences of the other irregular
/// vertices sharing a face with v, summed once each; valence_of[w] is w's valence where w is
/// irregular, else 0.
int nearby_valence(const PolyMesh& m, int v, const std::vector<int>& valence_of);

/// What the output is: a B-rep (STEP / IGES / BREP) or not (patch JSON, check); packed faces
/// or one per quad.
struct EstimateOptions {
  bool build_brep = true;
  bool packed = true;
  bool polar = true;     ///< polar structures become caps (PatchOptions::polar)
  bool quality = false;  ///< the quality stage (convert --report, check): Stam's eigenbases per valence
  /// The tolerance deepens some fans: the patches are built again while the first build is
  /// held, every fan's piece (and its nearby stars) twice at the peak, and built twice.
  bool rebuilt = false;
  /// Before any work, with a tolerance to meet (relative to the model size; 0: none, the levels
  /// are pinned) and the cage's positions: a fan of valence above kSharedPieceValence whose star
  /// is not flat is costed at the levels that take a deviation of kPredictedDeviation of the model
  /// size down to the tolerance at its deviation_rate (the wavy 1000-gon: 12 levels as built, 11
  /// predicted); a flat star is not deepened (the flat 1000-gon).
  double tolerance = 0;
  const std::vector<Point3>* positions = nullptr;
};

/// The deviation (relative to the model size) a curved high-valence fan is assumed to have at
/// its minimum levels, for the prediction above.
constexpr double kPredictedDeviation = 1e-2;

ResourceEstimate operator+(const ResourceEstimate& a, const ResourceEstimate& b);
ResourceEstimate operator-(const ResourceEstimate& a, const ResourceEstimate& b);

/// Conversion with `extra_levels` beyond the minimum at every fan, before any work: from the
/// quads of the coarsest all-quad mesh, its irregular vertices (valence, quads at each), the
/// semi-sharp edges (the builder refines along them until their sharpness decays) and the
/// output. Regular quads cost one piece and 16 poles each and pack into few faces; a quad at an
/// irregular vertex costs 3 pieces per level down to its zone and a patch of (levels + 7)^2
/// poles, one B-rep face of its own.
ResourceEstimate estimate_conversion(const SubdivLevel& base, int extra_levels, const EstimateOptions& options = {});
ResourceEstimate estimate_conversion(const SubdivLevel& base, int extra_levels, bool build_brep);

/// The same with the fans as the patch builder found them (the levels a tolerance gave each):
/// `fans` replace the irregular vertices the topology predicts.
ResourceEstimate estimate_conversion(const SubdivLevel& base, const std::vector<FanCost>& fans,
                                     const EstimateOptions& options = {});

/// What one fan adds to an estimate (estimate_conversion is the cage's part plus every fan's):
/// the difference of two of them is what deepening that fan costs.
ResourceEstimate fan_estimate(const FanCost& fan, const EstimateOptions& options = {});

/// Uniform refinement to `levels`: faces exact (corners x 4^(levels-1) after the first level).
ResourceEstimate estimate_refinement(const SubdivLevel& base, int levels);

/// A refusal: the estimate exceeds a limit. A SettingsError's sibling; the message names the
/// estimate, the limit and the overrides (--max-faces / --max-memory, Python max_faces= /
/// max_memory=).
class ResourceError : public Error {
 public:
  explicit ResourceError(const std::string& message) : Error(ErrorKind::Resources, message) {}
};

/// \throw ResourceError naming `what` ("converting at level 2", "refining to level 11")
void check_resources(const ResourceEstimate& estimate, const ResourceLimits& limits, double default_max_faces,
                     const std::string& what, const std::string& advice);

/// Human-readable byte count ("1.5 GiB").
std::string bytes_text(double bytes);

/// Parses a memory size: a number of bytes with an optional K, M, G or T suffix (powers of
/// 1024, "B" / "iB" allowed after it): "8G", "512MiB", "1e9". Returns false when malformed
/// or not positive.
bool parse_memory_size(const std::string& text, double& bytes);

}  // namespace subd2nurbs::pipeline
