#include "io/gltf_preview.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>

#include "io/atomic_file.h"
#include "io/input_error.h"

namespace subd2nurbs {

namespace {

int add_view(tinygltf::Model& model, std::vector<unsigned char>& data, const void* src, size_t bytes,
             int target) {
  while (data.size() % 4) data.push_back(0);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = data.size();
  view.byteLength = bytes;
  view.target = target;
  const size_t at = data.size();
  data.resize(at + bytes);
  std::memcpy(data.data() + at, src, bytes);
  model.bufferViews.push_back(view);
  return static_cast<int>(model.bufferViews.size()) - 1;
}

int add_vec3(tinygltf::Model& model, std::vector<unsigned char>& data, const std::vector<float>& v,
             bool bounds) {
  tinygltf::Accessor a;
  a.bufferView = add_view(model, data, v.data(), v.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
  a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  a.count = v.size() / 3;
  a.type = TINYGLTF_TYPE_VEC3;
  if (bounds && !v.empty()) {
    std::vector<double> lo(3, 1e300), hi(3, -1e300);
    for (size_t i = 0; i < v.size(); ++i) {
      lo[i % 3] = std::min(lo[i % 3], static_cast<double>(v[i]));
      hi[i % 3] = std::max(hi[i % 3], static_cast<double>(v[i]));
    }
    a.minValues = lo;
    a.maxValues = hi;
  }
  model.accessors.push_back(a);
  return static_cast<int>(model.accessors.size()) - 1;
}

}  // namespace

StagedFile stage_preview_glb(const std::string& path, const PreviewMesh& mesh, const std::string& title) {
  tinygltf::Model model;
  std::vector<unsigned char> data;
  tinygltf::Primitive prim;
  prim.attributes["POSITION"] = add_vec3(model, data, mesh.positions, true);
  prim.attributes["NORMAL"] = add_vec3(model, data, mesh.normals, false);
  prim.attributes["COLOR_0"] = add_vec3(model, data, mesh.colors, false);
  tinygltf::Accessor idx;
  idx.bufferView = add_view(model, data, mesh.indices.data(), mesh.indices.size() * sizeof(std::uint32_t),
                            TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  idx.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
  idx.count = mesh.indices.size();
  idx.type = TINYGLTF_TYPE_SCALAR;
  model.accessors.push_back(idx);
  prim.indices = static_cast<int>(model.accessors.size()) - 1;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  tinygltf::Material mat;
  mat.name = "vertex colours";
  mat.pbrMetallicRoughness.baseColorFactor = {1, 1, 1, 1};
  mat.pbrMetallicRoughness.metallicFactor = 0;
  mat.pbrMetallicRoughness.roughnessFactor = 1;
  mat.doubleSided = true;
  model.materials.push_back(mat);
  prim.material = 0;
  tinygltf::Buffer buffer;
  buffer.data = std::move(data);
  model.buffers.push_back(std::move(buffer));
  tinygltf::Mesh m;
  m.name = title;
  m.primitives.push_back(prim);
  model.meshes.push_back(m);
  tinygltf::Node node;
  node.mesh = 0;
  node.name = title;
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes = {0};
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  model.asset.version = "2.0";
  model.asset.generator = "subd2nurbs preview";
  StagedFile file(path);
  file.write([&](std::ostream& out) {
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&model, out, false, true))
      throw WriteError(path, "tinygltf could not write the preview");
  });
  return file;
}

void write_preview_glb(const std::string& path, const PreviewMesh& mesh, const std::string& title) {
  stage_preview_glb(path, mesh, title).commit();
}

}  // namespace subd2nurbs
