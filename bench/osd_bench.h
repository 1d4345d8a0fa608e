// OpenSubdiv set-up shared by the benchmarks: the refiner of an untagged cage (boundary rule
// edge-and-corner, like our default) and the point type of primvar interpolation.
#pragma once

#include <memory>

#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include "core/mesh/mesh_input.h"
#include "oracle/osd_reference.h"  // Vertex3 (header only: no link to the test library)

namespace subd2nurbs::bench {

using testing::Vertex3;

inline std::unique_ptr<OpenSubdiv::Far::TopologyRefiner> osd_refiner(const MeshInput& in) {
  namespace Far = OpenSubdiv::Far;
  namespace Sdc = OpenSubdiv::Sdc;
  Far::TopologyDescriptor desc;
  desc.numVertices = in.num_vertices();
  desc.numFaces = in.num_faces();
  desc.numVertsPerFace = in.face_sizes.data();
  desc.vertIndicesPerFace = in.face_indices.data();
  Sdc::Options opt;
  opt.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  return std::unique_ptr<Far::TopologyRefiner>(Factory::Create(desc, Factory::Options(Sdc::SCHEME_CATMARK, opt)));
}

}  // namespace subd2nurbs::bench
