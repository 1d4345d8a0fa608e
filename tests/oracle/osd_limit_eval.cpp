#include "osd_limit_eval.h"

#include <stdexcept>
#include <string>
#include <vector>

#include <opensubdiv/far/patchMap.h>
#include <opensubdiv/far/patchTable.h>
#include <opensubdiv/far/patchTableFactory.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/ptexIndices.h>
#include <opensubdiv/far/stencilTable.h>

#include "osd_reference.h"

namespace subd2nurbs::testing {

namespace Far = OpenSubdiv::Far;

namespace {


}  // namespace

struct OsdLimitEvaluator::Impl {
  std::unique_ptr<Far::PatchTable> patches;
  std::unique_ptr<Far::PatchMap> map;
  std::vector<Vertex3> points;  ///< every refined vertex of every level, then the local points
  int num_ptex = 0;
};

OsdLimitEvaluator::OsdLimitEvaluator(const MeshInput& input, int isolation_level)
    : impl_(std::make_unique<Impl>()) {
  if (isolation_level < 1 || isolation_level > 10)
    throw std::invalid_argument("OsdLimitEvaluator: isolation level must be in 1..10");
  std::unique_ptr<Far::TopologyRefiner> refiner = osd_create_refiner(input);
  if (!refiner) return;

  // Two departures from OpenSubdiv's defaults, both so that a REGULAR patch is always an exact
  // piece of the limit surface (checked in test_osd_limit_eval.cpp against limit_stencils):
  // - useInfSharpPatch: otherwise faces along an infinitely sharp crease are isolated to the
  //   last level and then given smooth REGULAR patches that ignore the crease (errors ~1e-5).
  //   With it they get exact regular patches with a sharp (boundary-like) side.
  // - no legacy sharp-corner patches: otherwise a smooth corner (a boundary vertex with one
  //   face under BoundaryRule::EdgeOnly) gets a REGULAR patch with a sharp corner, which is not
  //   the limit surface there; without it that patch is isolated and capped.
  // Everything else is the default: secondary level, no single-crease patches, Gregory-basis
  // end caps (in double precision).
  Far::PatchTableFactory::Options popt(isolation_level);
  popt.useInfSharpPatch = true;
  popt.generateLegacySharpCornerPatches = false;
  popt.SetEndCapType(Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
  popt.SetPatchPrecision<double>();
  refiner->RefineAdaptive(popt.GetRefineAdaptiveOptions());  // the matching adaptive options
  impl_->patches.reset(Far::PatchTableFactory::Create(*refiner, popt));
  if (!impl_->patches) return;

  // Positions of every level in one array (the numbering patch vertices use), then local points.
  const int num_refined = refiner->GetNumVerticesTotal();
  const int num_local = impl_->patches->GetNumLocalPoints();
  std::vector<Vertex3>& pts = impl_->points;
  pts.resize(static_cast<size_t>(num_refined) + num_local);
  for (int v = 0; v < input.num_vertices(); ++v)
    for (int k = 0; k < 3; ++k) pts[v].p[k] = input.positions[v][k];
  Far::PrimvarRefinerReal<double> primvar(*refiner);
  Vertex3* src = pts.data();
  for (int level = 1; level < refiner->GetNumLevels(); ++level) {
    Vertex3* dst = src + refiner->GetLevel(level - 1).GetNumVertices();
    primvar.Interpolate(level, src, dst);
    src = dst;
  }
  if (num_local > 0) {
    const Far::StencilTableReal<double>* local = impl_->patches->GetLocalPointStencilTable<double>();
    if (!local) throw std::logic_error("OsdLimitEvaluator: no double local point stencils");
    local->UpdateValues(pts.data(), pts.data() + num_refined);
  }
  impl_->map = std::make_unique<Far::PatchMap>(*impl_->patches);
  impl_->num_ptex = Far::PtexIndices(*refiner).GetNumFaces();
}

OsdLimitEvaluator::~OsdLimitEvaluator() = default;
OsdLimitEvaluator::OsdLimitEvaluator(OsdLimitEvaluator&&) noexcept = default;
OsdLimitEvaluator& OsdLimitEvaluator::operator=(OsdLimitEvaluator&&) noexcept = default;

bool OsdLimitEvaluator::ok() const { return impl_ && impl_->map != nullptr; }

int OsdLimitEvaluator::num_ptex_faces() const { return ok() ? impl_->num_ptex : 0; }

OsdLimitEvaluator::Sample OsdLimitEvaluator::eval(int ptex_face, double u, double v) const {
  if (!ok()) throw std::out_of_range("OsdLimitEvaluator: OpenSubdiv rejected the mesh");
  if (ptex_face < 0 || ptex_face >= impl_->num_ptex)
    throw std::out_of_range("OsdLimitEvaluator: no ptex face " + std::to_string(ptex_face));
  const Far::PatchTable::PatchHandle* h = impl_->map->FindPatch(ptex_face, u, v);
  if (!h)
    throw std::out_of_range("OsdLimitEvaluator: ptex face " + std::to_string(ptex_face) +
                            " has no patch at (" + std::to_string(u) + ", " + std::to_string(v) + ")");
  const Far::PatchTable& table = *impl_->patches;
  double wp[20], wu[20], wv[20];  // at most 20 points (Gregory basis)
  table.EvaluateBasis(*h, u, v, wp, wu, wv);
  Far::ConstIndexArray cvs = table.GetPatchVertices(*h);
  Sample s;
  for (int i = 0; i < cvs.size(); ++i) {
    const Vertex3& c = impl_->points[cvs[i]];
    for (int k = 0; k < 3; ++k) {
      s.p[k] += wp[i] * c.p[k];
      s.du[k] += wu[i] * c.p[k];
      s.dv[k] += wv[i] * c.p[k];
    }
  }
  s.regular_patch = table.GetPatchDescriptor(*h).GetType() == Far::PatchDescriptor::REGULAR;
  return s;
}

}  // namespace subd2nurbs::testing
