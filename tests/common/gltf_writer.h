// Test helper: a cage as glTF triangles, the way exporters write it (each quad split along a
// diagonal, optionally every triangle with its own three vertices as at flat-shaded normal
// seams, a node transform). Uses Debian's shared libtinygltf (link TinyGLTF::TinyGLTF).
#pragma once

#include <tiny_gltf.h>

#include <array>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/mesh/mesh_input.h"

namespace subd2nurbs::testing {

struct GltfOptions {
  bool second_diagonal = false;  ///< split quads along 1-3 instead of 0-2
  bool split_vertices = false;   ///< three fresh vertices per triangle
  std::array<double, 3> translation{0, 0, 0};
  bool binary = true;            ///< .glb, else .gltf with the buffer embedded
};

/// Triangles of `m`: quads split along a diagonal, triangles kept; other faces fanned.
inline std::vector<std::array<int, 3>> cage_triangles(const MeshInput& m, bool second_diagonal) {
  std::vector<std::array<int, 3>> tris;
  size_t o = 0;
  for (int n : m.face_sizes) {
    const int* v = m.face_indices.data() + o;
    o += static_cast<size_t>(n);
    const int s = (n == 4 && second_diagonal) ? 1 : 0;
    for (int k = 1; k + 1 < n; ++k) tris.push_back({v[s], v[(s + k) % n], v[(s + k + 1) % n]});
  }
  return tris;
}

inline void write_gltf(const MeshInput& m, const std::string& path, const GltfOptions& o = {}) {
  const auto tris = cage_triangles(m, o.second_diagonal);
  std::vector<float> xyz;
  std::vector<std::uint32_t> idx;
  auto push = [&xyz](const std::array<double, 3>& p) {
    for (double c : p) xyz.push_back(static_cast<float>(c));
  };
  if (o.split_vertices) {
    for (const auto& t : tris)
      for (int v : t) {
        idx.push_back(static_cast<std::uint32_t>(xyz.size() / 3));
        push(m.positions[static_cast<size_t>(v)]);
      }
  } else {
    for (const auto& p : m.positions) push(p);
    for (const auto& t : tris)
      for (int v : t) idx.push_back(static_cast<std::uint32_t>(v));
  }
  tinygltf::Model model;
  tinygltf::Buffer buffer;
  buffer.data.resize(xyz.size() * 4 + idx.size() * 4);
  std::memcpy(buffer.data.data(), xyz.data(), xyz.size() * 4);
  std::memcpy(buffer.data.data() + xyz.size() * 4, idx.data(), idx.size() * 4);
  model.buffers.push_back(buffer);
  tinygltf::BufferView positions_view, index_view;
  positions_view.buffer = 0;
  positions_view.byteOffset = 0;
  positions_view.byteLength = xyz.size() * 4;
  positions_view.target = TINYGLTF_TARGET_ARRAY_BUFFER;
  index_view.buffer = 0;
  index_view.byteOffset = xyz.size() * 4;
  index_view.byteLength = idx.size() * 4;
  index_view.target = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
  model.bufferViews = {positions_view, index_view};
  tinygltf::Accessor positions, indices;
  positions.bufferView = 0;
  positions.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  positions.count = xyz.size() / 3;
  positions.type = TINYGLTF_TYPE_VEC3;
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (size_t i = 0; i < xyz.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], static_cast<double>(xyz[i]));
    hi[i % 3] = std::max(hi[i % 3], static_cast<double>(xyz[i]));
  }
  positions.minValues = {lo[0], lo[1], lo[2]};
  positions.maxValues = {hi[0], hi[1], hi[2]};
  indices.bufferView = 1;
  indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
  indices.count = idx.size();
  indices.type = TINYGLTF_TYPE_SCALAR;
  model.accessors = {positions, indices};
  tinygltf::Primitive prim;
  prim.attributes["POSITION"] = 0;
  prim.indices = 1;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  tinygltf::Mesh mesh;
  mesh.primitives.push_back(prim);
  model.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  if (o.translation != std::array<double, 3>{0, 0, 0})
    node.translation = {o.translation[0], o.translation[1], o.translation[2]};
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes = {0};
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  model.asset.version = "2.0";
  model.asset.generator = "subd2nurbs tests";
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToFile(&model, path, true, true, true, o.binary))
    throw std::runtime_error("could not write " + path);
}

}  // namespace subd2nurbs::testing
