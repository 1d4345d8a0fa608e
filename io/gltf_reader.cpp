#include "core/util/number_text.h"
#include "io/gltf_reader.h"

#include <tiny_gltf.h>

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <new>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/mesh/quad_recovery.h"
#include "core/mesh/validate.h"
#include "io/input_file.h"
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

std::string coordinate_text(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", x);
  return buffer;
}

class Reader {
 public:
  Reader(const std::string& path, const tinygltf::Model& model, const GltfLimits& limits)
      : path_(path), model_(model), limits_(limits) {}

  [[noreturn]] void fail(const std::string& message) const { throw InputError(path_, 0, message); }

  /// An accessor's elements, checked against its buffer view and buffer before anything is
  /// allocated from its `count`.
  struct Span {
    const unsigned char* base = nullptr;
    size_t stride = 0, count = 0;
    const unsigned char* at(size_t i) const { return base + i * stride; }
  };

  /// "accessor 3 (POSITION of mesh 0 primitive 1)".
  static std::string accessor_name(int index, const std::string& role) {
    return "accessor " + std::to_string(index) + " (" + role + ")";
  }

  Span span(int index, const std::string& role, size_t element_size) const {
    const std::string name = accessor_name(index, role);
    if (index < 0 || index >= static_cast<int>(model_.accessors.size())) fail(name + " does not exist");
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(index)];
    if (a.sparse.isSparse) fail(name + ": sparse accessors are not supported");
    if (a.bufferView < 0 || a.bufferView >= static_cast<int>(model_.bufferViews.size()))
      fail(name + " has no buffer view");
    const tinygltf::BufferView& view = model_.bufferViews[static_cast<size_t>(a.bufferView)];
    const std::string view_name = "buffer view " + std::to_string(a.bufferView);
    if (view.buffer < 0 || view.buffer >= static_cast<int>(model_.buffers.size()))
      fail(name + ": " + view_name + " has no buffer");
    const tinygltf::Buffer& buffer = model_.buffers[static_cast<size_t>(view.buffer)];
    const size_t available = buffer.data.size();
    if (view.byteOffset > available || view.byteLength > available - view.byteOffset)
      fail(name + ": " + view_name + " (offset " + std::to_string(view.byteOffset) + ", " +
           std::to_string(view.byteLength) + " bytes) lies outside buffer " + std::to_string(view.buffer) + " (" +
           std::to_string(available) + " bytes)");
    Span s;
    s.stride = view.byteStride > 0 ? view.byteStride : element_size;
    s.count = a.count;
    if (s.stride < element_size)
      fail(name + ": " + view_name + "'s byteStride " + std::to_string(view.byteStride) +
           " is smaller than an element (" + std::to_string(element_size) + " bytes)");
    // The last element must end inside the view: count is bounded by the bytes present.
    const size_t room = view.byteLength;
    const bool fits = s.count == 0 ? a.byteOffset <= room
                                   : a.byteOffset <= room && element_size <= room - a.byteOffset &&
                                         s.count - 1 <= (room - a.byteOffset - element_size) / s.stride;
    if (!fits)
      fail(name + ": count " + std::to_string(a.count) + " needs more bytes than its " + view_name +
           " holds (" + std::to_string(view.byteLength) + " bytes from offset " + std::to_string(a.byteOffset) + ")");
    s.base = buffer.data.data() + view.byteOffset + a.byteOffset;
    return s;
  }

  std::vector<std::array<double, 3>> positions(int accessor, const std::string& role) const {
    if (accessor < 0 || accessor >= static_cast<int>(model_.accessors.size()))
      fail(accessor_name(accessor, role) + " does not exist");
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(accessor)];
    if (a.type != TINYGLTF_TYPE_VEC3 || a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
      fail(accessor_name(accessor, role) + ": POSITION must be VEC3 of FLOAT");
    float xyz[3];
    const Span s = span(accessor, role, sizeof xyz);
    std::vector<std::array<double, 3>> p(s.count);
    for (size_t i = 0; i < s.count; ++i) {
      std::memcpy(xyz, s.at(i), sizeof xyz);
      for (int k = 0; k < 3; ++k)
        if (!std::isfinite(xyz[k]))
          fail(accessor_name(accessor, role) + ": element " + std::to_string(i) + " has a non-finite " +
               "xyz"[k] + " coordinate (" + (std::isnan(xyz[k]) ? "NaN" : "Inf") + ")");
      p[i] = {xyz[0], xyz[1], xyz[2]};
    }
    return p;
  }

  std::vector<long> indices(int accessor, size_t vertex_count, const std::string& role) const {
    std::vector<long> out;
    if (accessor < 0) {  // non-indexed: consecutive triples
      out.resize(vertex_count);
      for (size_t i = 0; i < vertex_count; ++i) out[i] = static_cast<long>(i);
      return out;
    }
    if (accessor >= static_cast<int>(model_.accessors.size())) fail(accessor_name(accessor, role) + " does not exist");
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(accessor)];
    if (a.type != TINYGLTF_TYPE_SCALAR) fail(accessor_name(accessor, role) + ": indices must be SCALAR");
    size_t size = 0;
    switch (a.componentType) {
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: size = 1; break;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: size = 2; break;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: size = 4; break;
      default: fail(accessor_name(accessor, role) + ": indices must be unsigned byte, short or int");
    }
    const Span s = span(accessor, role, size);
    out.resize(s.count);
    for (size_t i = 0; i < s.count; ++i) {
      if (size == 1) {
        out[i] = *s.at(i);
      } else if (size == 2) {
        std::uint16_t v;
        std::memcpy(&v, s.at(i), 2);
        out[i] = v;
      } else {
        std::uint32_t v;
        std::memcpy(&v, s.at(i), 4);
        out[i] = v;
      }
    }
    return out;
  }

  /// Triangles a primitive brings, from its counts alone (nothing is read).
  size_t triangle_count(const tinygltf::Primitive& prim) const {
    const int accessor = prim.indices >= 0 ? prim.indices : [&] {
      const auto it = prim.attributes.find("POSITION");
      return it == prim.attributes.end() ? -1 : it->second;
    }();
    if (accessor < 0 || accessor >= static_cast<int>(model_.accessors.size())) return 0;
    return model_.accessors[static_cast<size_t>(accessor)].count / 3;
  }

  /// Appends the triangles of mesh `m` transformed by `x`, welding vertices by position.
  void add_mesh(int m, const Matrix& x, const std::string& where) {
    if (m < 0 || m >= static_cast<int>(model_.meshes.size()))
      fail(where + " refers to mesh " + std::to_string(m) + ", which does not exist");
    const auto& primitives = model_.meshes[static_cast<size_t>(m)].primitives;
    for (size_t pi = 0; pi < primitives.size(); ++pi) {
      const tinygltf::Primitive& prim = primitives[pi];
      const std::string prim_name = "mesh " + std::to_string(m) + " primitive " + std::to_string(pi);
      if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES)
        fail(prim_name + ": mode " + std::to_string(prim.mode) + " is not supported (only triangles, mode 4)");
      // Instances multiply triangles: refuse before reading anything.
      triangles_ += static_cast<long>(std::min(triangle_count(prim), static_cast<size_t>(limits_.instanced_triangles)));
      if (triangles_ > limits_.instanced_triangles)
        fail(where + ": instancing " + prim_name + " here brings the scene to more than " +
             std::to_string(limits_.instanced_triangles) + " triangles (each path from the scene to a node is one "
             "instance of its mesh)");
      const auto it = prim.attributes.find("POSITION");
      if (it == prim.attributes.end()) fail(prim_name + " has no POSITION attribute");
      // Every instance transforms and welds all of the primitive's vertices, used or not.
      if (it->second >= 0 && it->second < static_cast<int>(model_.accessors.size()))
        vertices_ += static_cast<long>(
            std::min(model_.accessors[static_cast<size_t>(it->second)].count,
                     static_cast<size_t>(limits_.instanced_triangles)));
      if (vertices_ > limits_.instanced_triangles)
        fail(where + ": instancing " + prim_name + " here brings the scene to more than " +
             std::to_string(limits_.instanced_triangles) + " vertices (each path from the scene to a node is one "
             "instance of its mesh)");
      const std::vector<std::array<double, 3>> local = positions(it->second, "POSITION of " + prim_name);
      const std::vector<long> idx = indices(prim.indices, local.size(), "indices of " + prim_name);
      if (idx.size() % 3 != 0)
        fail(prim_name + " has " + std::to_string(idx.size()) + " indices, not a multiple of 3");
      std::vector<int> id(local.size());
      for (size_t i = 0; i < local.size(); ++i) {
        const auto& p = local[i];
        std::array<double, 3> q;
        for (int r = 0; r < 3; ++r) q[r] = x[r] * p[0] + x[4 + r] * p[1] + x[8 + r] * p[2] + x[12 + r];
        for (int r = 0; r < 3; ++r)
          if (!(std::fabs(q[r]) <= kMaxCoordinate))
            fail(where + ", " + prim_name + ": vertex " + std::to_string(i) + " is transformed to " + "xyz"[r] +
                 " = " + exact_number_text(q[r]) + ", beyond the coordinate limit +-" + coordinate_text(kMaxCoordinate));
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
            fail(prim_name + ": triangle " + std::to_string(t / 3) + " uses index " + std::to_string(v) +
                 ", out of range (the primitive has " + std::to_string(local.size()) + " vertices)");
        if (det < 0) std::swap(tri[1], tri[2]);
        mesh_.face_sizes.push_back(3);
        for (long v : tri) mesh_.face_indices.push_back(id[static_cast<size_t>(v)]);
      }
    }
  }

  void add_node(int n, const Matrix& parent, int depth) {
    if (n < 0 || n >= static_cast<int>(model_.nodes.size()))
      fail("the scene refers to node " + std::to_string(n) + ", which does not exist");
    const std::string where = "node " + std::to_string(n);
    if (depth > 64) fail(where + ": the node hierarchy is deeper than 64 (a cycle?)");
    if (++instances_ > limits_.node_instances)
      fail(where + ": the scene expands to more than " + std::to_string(limits_.node_instances) +
           " node instances (a node listed as a child several times is instanced once per path)");
    const tinygltf::Node& node = model_.nodes[static_cast<size_t>(n)];
    const Matrix local = local_transform(node);
    for (double v : local)
      if (!std::isfinite(v)) fail(where + ": its transform (matrix, translation, rotation or scale) is not finite");
    const Matrix x = multiply(parent, local);
    if (node.mesh >= 0) add_mesh(node.mesh, x, where);
    for (int c : node.children) add_node(c, x, depth + 1);
  }

  MeshInput read() {
    if (!model_.scenes.empty()) {
      const int s = model_.defaultScene >= 0 && model_.defaultScene < static_cast<int>(model_.scenes.size())
                        ? model_.defaultScene
                        : 0;
      for (int n : model_.scenes[static_cast<size_t>(s)].nodes) add_node(n, identity(), 0);
    } else {
      for (size_t m = 0; m < model_.meshes.size(); ++m) add_mesh(static_cast<int>(m), identity(), "the file (no scene)");
    }
    if (mesh_.face_sizes.empty()) fail("no triangles in the scene");
    return std::move(mesh_);
  }

 private:
  std::string path_;
  const tinygltf::Model& model_;
  GltfLimits limits_;
  MeshInput mesh_;
  std::map<std::array<double, 3>, int> weld_;
  long instances_ = 0;
  long triangles_ = 0;
  long vertices_ = 0;
};

/// tinygltf reads external buffers (a .gltf's "uri") through this: regular files only and
/// the same size cap as the main file (io/input_file.h), so a buffer naming a FIFO or a
/// device neither blocks nor reads forever.
bool read_external_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void*) {
  try {
    const std::string bytes = read_input_file(path, "a glTF buffer");
    out->assign(bytes.begin(), bytes.end());
    return true;
  } catch (const InputError& e) {
    if (err) *err += e.what() + std::string("\n");
    return false;
  }
}

/// tinygltf's own FileExists opens the file (fopen), which blocks on a FIFO: stat instead.
/// A file that exists but is not regular is then refused by read_external_file.
bool external_file_exists(const std::string& path, void*) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

/// Reading a cage never writes.
bool refuse_write(std::string* err, const std::string& path, const std::vector<unsigned char>&, void*) {
  if (err) *err += "not writing " + printable(path) + "\n";
  return false;
}

}  // namespace

LoadedCage read_gltf(const std::string& path) {
  const bool binary = lowercase_extension(path) == ".glb";
  return parse_gltf(read_input_file(path, binary ? "a GLB file" : "a glTF file"), path, binary,
                    std::filesystem::path(path).parent_path().string());
}

LoadedCage parse_gltf(const std::string& file_bytes, const std::string& path, bool binary, const std::string& base_dir,
                      const GltfLimits& limits) {
  std::string_view bytes = file_bytes;
  if (!binary) {
    using namespace std::string_view_literals;
    if (bytes.substr(0, 3) == "\xEF\xBB\xBF"sv) bytes.remove_prefix(3);  // UTF-8 byte-order mark
    if (bytes.substr(0, 2) == "\xFF\xFE"sv || bytes.substr(0, 2) == "\xFE\xFF"sv)
      throw InputError(path, 0, "the file is UTF-16 encoded; glTF JSON must be UTF-8");
  }
  if (bytes.size() > std::numeric_limits<unsigned int>::max())
    throw InputError(path, 0, "the file is larger than 4 GiB, which glTF does not allow");
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  // Images are irrelevant to a cage: do not decode them.
  loader.SetImageLoader(
      [](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
        return true;
      },
      nullptr);
  tinygltf::FsCallbacks fs{&external_file_exists, &tinygltf::ExpandFilePath, &read_external_file, &refuse_write,
                           nullptr};
  loader.SetFsCallbacks(fs);
  std::string error, warning;
  const auto size = static_cast<unsigned int>(bytes.size());
  bool ok = false;
  try {
    ok = binary ? loader.LoadBinaryFromMemory(&model, &error, &warning,
                                              reinterpret_cast<const unsigned char*>(bytes.data()), size, base_dir)
                : loader.LoadASCIIFromString(&model, &error, &warning, bytes.data(), size, base_dir);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    // tinygltf itself throws on some malformed files (e.g. std::out_of_range for a GLB whose
    // buffer 0 is empty though a BIN chunk follows, found by fuzz_gltf): the file is bad.
    error = std::string("the glTF loader failed: ") + e.what();
  }
  if (!ok) {
    while (!error.empty() && std::isspace(static_cast<unsigned char>(error.back()))) error.pop_back();
    throw InputError(path, 0, "not a readable glTF file: " +
                                  (error.empty() ? std::string("unknown error") : printable(error, 400)));
  }
  Reader reader(path, model, limits);
  const MeshInput triangles = reader.read();

  LoadedCage cage;
  cage.path = path;
  take_recovered_quads(cage, recover_quads(triangles));
  if (!warning.empty()) {
    while (!warning.empty() && std::isspace(static_cast<unsigned char>(warning.back()))) warning.pop_back();
    cage.diagnostics.push_back({"gltf-warning", ElementKind::None, 0, printable(warning, 400)});
  }
  return cage;
}

}  // namespace subd2nurbs
