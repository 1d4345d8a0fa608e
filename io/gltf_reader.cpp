#include "io/gltf_reader.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <vector>

#include "core/mesh/quad_recovery.h"
#include "io/input_error.h"

namespace subd2nurbs {

namespace {

using Matrix = std::array<double, 16>;  // column-major, as glTF

Matrix identity() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }

Matrix multiply(const Matrix& a, const Matrix& b) {
  Matrix r{};
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a[k * 4 + row] * b[c * 4 + k];
      r[c * 4 + row] = s;
    }
  return r;
}

/// The node's local transform: its matrix, or T * R * S.
Matrix local_transform(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) {
    Matrix m;
    std::copy(node.matrix.begin(), node.matrix.end(), m.begin());
    return m;
  }
  Matrix t = identity(), r = identity(), s = identity();
  if (node.translation.size() == 3) {
    t[12] = node.translation[0];
    t[13] = node.translation[1];
    t[14] = node.translation[2];
  }
  if (node.rotation.size() == 4) {
    const double x = node.rotation[0], y = node.rotation[1], z = node.rotation[2], w = node.rotation[3];
    r = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),     0,
         2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),     0,
         2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y), 0,
         0,                       0,                       0,                       1};
  }
  if (node.scale.size() == 3) {
    s[0] = node.scale[0];
    s[5] = node.scale[1];
    s[10] = node.scale[2];
  }
  return multiply(t, multiply(r, s));
}

class Reader {
 public:
  Reader(const std::string& path, const tinygltf::Model& model) : path_(path), model_(model) {}

  [[noreturn]] void fail(const std::string& message) const { throw InputError(path_, 0, message); }

  /// Bytes of element i of an accessor (checked against the buffer).
  const unsigned char* element(const tinygltf::Accessor& a, size_t i, size_t element_size) const {
    if (a.sparse.isSparse) fail("sparse accessors are not supported");
    if (a.bufferView < 0 || a.bufferView >= static_cast<int>(model_.bufferViews.size()))
      fail("an accessor has no buffer view");
    const tinygltf::BufferView& view = model_.bufferViews[static_cast<size_t>(a.bufferView)];
    if (view.buffer < 0 || view.buffer >= static_cast<int>(model_.buffers.size())) fail("a buffer view has no buffer");
    const tinygltf::Buffer& buffer = model_.buffers[static_cast<size_t>(view.buffer)];
    const size_t stride = view.byteStride > 0 ? view.byteStride : element_size;
    const size_t begin = view.byteOffset + a.byteOffset + i * stride;
    if (begin + element_size > buffer.data.size() || begin + element_size > view.byteOffset + view.byteLength)
      fail("an accessor reads past the end of its buffer");
    return buffer.data.data() + begin;
  }

  std::vector<std::array<double, 3>> positions(int accessor) const {
    if (accessor < 0 || accessor >= static_cast<int>(model_.accessors.size())) fail("a primitive has no POSITION");
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(accessor)];
    if (a.type != TINYGLTF_TYPE_VEC3 || a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
      fail("POSITION must be VEC3 of FLOAT");
    std::vector<std::array<double, 3>> p(a.count);
    for (size_t i = 0; i < a.count; ++i) {
      float xyz[3];
      std::memcpy(xyz, element(a, i, sizeof xyz), sizeof xyz);
      p[i] = {xyz[0], xyz[1], xyz[2]};
    }
    return p;
  }

  std::vector<long> indices(int accessor, size_t vertex_count) const {
    std::vector<long> out;
    if (accessor < 0) {  // non-indexed: consecutive triples
      for (size_t i = 0; i < vertex_count; ++i) out.push_back(static_cast<long>(i));
      return out;
    }
    if (accessor >= static_cast<int>(model_.accessors.size())) fail("a primitive's indices accessor does not exist");
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(accessor)];
    if (a.type != TINYGLTF_TYPE_SCALAR) fail("indices must be SCALAR");
    for (size_t i = 0; i < a.count; ++i) {
      switch (a.componentType) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: out.push_back(*element(a, i, 1)); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
          std::uint16_t v;
          std::memcpy(&v, element(a, i, 2), 2);
          out.push_back(v);
          break;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
          std::uint32_t v;
          std::memcpy(&v, element(a, i, 4), 4);
          out.push_back(v);
          break;
        }
        default: fail("indices must be unsigned byte, short or int");
      }
    }
    return out;
  }

  /// Appends the triangles of mesh `m` transformed by `x`, welding vertices by position.
  void add_mesh(int m, const Matrix& x) {
    if (m < 0 || m >= static_cast<int>(model_.meshes.size())) fail("a node refers to a missing mesh");
    for (const tinygltf::Primitive& prim : model_.meshes[static_cast<size_t>(m)].primitives) {
      if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES)
        fail("primitive mode " + std::to_string(prim.mode) + " is not supported (only triangles, mode 4)");
      const auto it = prim.attributes.find("POSITION");
      if (it == prim.attributes.end()) fail("a primitive has no POSITION attribute");
      const std::vector<std::array<double, 3>> local = positions(it->second);
      const std::vector<long> idx = indices(prim.indices, local.size());
      if (idx.size() % 3 != 0) fail("a triangle primitive has " + std::to_string(idx.size()) + " indices, not a multiple of 3");
      std::vector<int> id(local.size());
      for (size_t i = 0; i < local.size(); ++i) {
        const auto& p = local[i];
        std::array<double, 3> q;
        for (int r = 0; r < 3; ++r) q[r] = x[r] * p[0] + x[4 + r] * p[1] + x[8 + r] * p[2] + x[12 + r];
        const auto found = weld_.find(q);
        if (found != weld_.end()) {
          id[i] = found->second;
        } else {
          id[i] = static_cast<int>(mesh_.positions.size());
          weld_.emplace(q, id[i]);
          mesh_.positions.push_back(q);
        }
      }
      // A transform that mirrors (negative determinant) flips the triangles' orientation.
      const double det = x[0] * (x[5] * x[10] - x[9] * x[6]) - x[4] * (x[1] * x[10] - x[9] * x[2]) +
                         x[8] * (x[1] * x[6] - x[5] * x[2]);
      for (size_t t = 0; t + 2 < idx.size(); t += 3) {
        std::array<long, 3> tri = {idx[t], idx[t + 1], idx[t + 2]};
        for (long v : tri)
          if (v < 0 || v >= static_cast<long>(local.size()))
            fail("triangle index " + std::to_string(v) + " out of range (the primitive has " +
                 std::to_string(local.size()) + " vertices)");
        if (det < 0) std::swap(tri[1], tri[2]);
        mesh_.face_sizes.push_back(3);
        for (long v : tri) mesh_.face_indices.push_back(id[static_cast<size_t>(v)]);
      }
    }
  }

  void add_node(int n, const Matrix& parent, int depth) {
    if (n < 0 || n >= static_cast<int>(model_.nodes.size())) fail("a scene refers to a missing node");
    if (depth > 64) fail("the node hierarchy is deeper than 64 (a cycle?)");
    const tinygltf::Node& node = model_.nodes[static_cast<size_t>(n)];
    const Matrix x = multiply(parent, local_transform(node));
    if (node.mesh >= 0) add_mesh(node.mesh, x);
    for (int c : node.children) add_node(c, x, depth + 1);
  }

  MeshInput read() {
    if (!model_.scenes.empty()) {
      const int s = model_.defaultScene >= 0 && model_.defaultScene < static_cast<int>(model_.scenes.size())
                        ? model_.defaultScene
                        : 0;
      for (int n : model_.scenes[static_cast<size_t>(s)].nodes) add_node(n, identity(), 0);
    } else {
      for (size_t m = 0; m < model_.meshes.size(); ++m) add_mesh(static_cast<int>(m), identity());
    }
    if (mesh_.face_sizes.empty()) fail("no triangles in the scene");
    return std::move(mesh_);
  }

 private:
  std::string path_;
  const tinygltf::Model& model_;
  MeshInput mesh_;
  std::map<std::array<double, 3>, int> weld_;
};

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

LoadedCage read_gltf(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path, 0, "cannot open the file (no such file)");
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  // Images are irrelevant to a cage: do not decode them.
  loader.SetImageLoader(
      [](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
        return true;
      },
      nullptr);
  std::string error, warning;
  const bool ok = lower_extension(path) == ".glb" ? loader.LoadBinaryFromFile(&model, &error, &warning, path)
                                                  : loader.LoadASCIIFromFile(&model, &error, &warning, path);
  if (!ok) {
    while (!error.empty() && std::isspace(static_cast<unsigned char>(error.back()))) error.pop_back();
    throw InputError(path, 0, "not a readable glTF file: " + (error.empty() ? std::string("unknown error") : error));
  }
  Reader reader(path, model);
  const MeshInput triangles = reader.read();

  LoadedCage cage;
  cage.path = path;
  const QuadRecoveryResult r = recover_quads(triangles);
  cage.input = r.mesh;
  cage.recovery.applied = true;
  cage.recovery.source_triangles = r.input_triangles;
  cage.recovery.quads = r.quads;
  cage.recovery.triangles_kept = r.triangles_kept;
  cage.recovery.fan_vertices = r.fan_vertices;
  if (!warning.empty()) {
    while (!warning.empty() && std::isspace(static_cast<unsigned char>(warning.back()))) warning.pop_back();
    cage.diagnostics.push_back({"gltf-warning", ElementKind::None, 0, warning});
  }
  return cage;
}

LoadedCage read_cage(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".glb" || ext == ".gltf") return read_gltf(path);
  return read_obj(path);
}

}  // namespace subd2nurbs
