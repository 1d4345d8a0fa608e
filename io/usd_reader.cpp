// USD to cage: the encoding chosen by content, the usdz package opened, then a small composition
// of the layer (variants, internal references, the prim hierarchy's transforms) and every Mesh
// prim mapped onto MeshInput as the OBJ tags would give it (io/usd_reader.h).
#include "io/usd_reader.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <set>

#include "core/util/error.h"
#include "io/input_error.h"
#include "io/input_file.h"
#include "io/usd_parsers.h"

namespace subd2nurbs {

namespace {

using usd::Attribute;
using usd::Layer;
using usd::PrimSpec;
using usd::Value;

using Matrix = std::array<double, 16>;  // row-major, acting on column vectors: p' = M p

Matrix identity() {
  Matrix m{};
  m[0] = m[5] = m[10] = m[15] = 1;
  return m;
}

Matrix multiply(const Matrix& a, const Matrix& b) {
  Matrix c{};
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 4; ++j) c[r * 4 + j] += a[r * 4 + k] * b[k * 4 + j];
  return c;
}

double determinant3(const Matrix& m) {
  return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) + m[2] * (m[4] * m[9] - m[5] * m[8]);
}

/// Inverse of an affine matrix (the last row 0 0 0 1); false when singular.
bool invert_affine(const Matrix& m, Matrix& out) {
  const double det = determinant3(m);
  if (!(std::abs(det) > 0) || !std::isfinite(det)) return false;
  out = identity();
  const double inv = 1 / det;
  out[0] = (m[5] * m[10] - m[6] * m[9]) * inv;
  out[1] = (m[2] * m[9] - m[1] * m[10]) * inv;
  out[2] = (m[1] * m[6] - m[2] * m[5]) * inv;
  out[4] = (m[6] * m[8] - m[4] * m[10]) * inv;
  out[5] = (m[0] * m[10] - m[2] * m[8]) * inv;
  out[6] = (m[2] * m[4] - m[0] * m[6]) * inv;
  out[8] = (m[4] * m[9] - m[5] * m[8]) * inv;
  out[9] = (m[1] * m[8] - m[0] * m[9]) * inv;
  out[10] = (m[0] * m[5] - m[1] * m[4]) * inv;
  for (int r = 0; r < 3; ++r) out[r * 4 + 3] = -(out[r * 4] * m[3] + out[r * 4 + 1] * m[7] + out[r * 4 + 2] * m[11]);
  return true;
}

Matrix rotation(int axis, double degrees) {
  const double a = degrees * M_PI / 180, c = std::cos(a), s = std::sin(a);
  Matrix m = identity();
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  m[i * 4 + i] = c;
  m[i * 4 + j] = -s;
  m[j * 4 + i] = s;
  m[j * 4 + j] = c;
  return m;
}

std::string number_text(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", x);
  return buffer;
}

// --- usdz ------------------------------------------------------------------------------------

/// The first USD layer of a usdz (zip) package: its bytes and encoding name.
std::string_view usdz_layer(std::string_view zip, const std::string& name, std::string& layer_name) {
  std::size_t at = 0;
  auto u16 = [&](std::size_t p) { return static_cast<std::uint32_t>(static_cast<unsigned char>(zip[p]) | (static_cast<unsigned char>(zip[p + 1]) << 8)); };
  auto u32 = [&](std::size_t p) { return u16(p) | (u16(p + 2) << 16); };
  while (at + 30 <= zip.size() && u32(at) == 0x04034b50u) {
    const std::uint32_t flags = u16(at + 6), method = u16(at + 8);
    const std::uint64_t size = u32(at + 18);
    const std::size_t name_length = u16(at + 26), extra = u16(at + 28);
    if (at + 30 + name_length + extra > zip.size()) throw InputError(name, 0, "usdz: a file header runs past the end of the package");
    const std::string entry(zip.substr(at + 30, name_length));
    const std::size_t data = at + 30 + name_length + extra;
    if (flags & 8) throw InputError(name, 0, "usdz: entry '" + printable(entry, 60) + "' has a data descriptor (not a valid usdz: entries are stored with their sizes)");
    if (size == 0xffffffffu) throw InputError(name, 0, "usdz: zip64 entries are not read");
    if (data + size > zip.size()) throw InputError(name, 0, "usdz: entry '" + printable(entry, 60) + "' runs past the end of the package (truncated?)");
    const std::string ext = lowercase_extension(entry);
    if (ext == ".usda" || ext == ".usdc" || ext == ".usd") {
      if (method != 0)
        throw InputError(name, 0, "usdz: entry '" + printable(entry, 60) + "' is compressed (method " + std::to_string(method) +
                                      "); usdz packages store their files uncompressed");
      layer_name = entry;
      return zip.substr(data, size);
    }
    at = data + size;
  }
  throw InputError(name, 0, "usdz: the package holds no .usda, .usdc or .usd layer");
}

// --- composition -----------------------------------------------------------------------------

/// A prim as composed: its specs, strongest first.
struct Composed {
  std::string path;
  std::vector<const PrimSpec*> specs;
};

class Reader {
 public:
  Reader(const Layer& layer, const std::string& name, const UsdReadOptions& options, LoadedCage& cage)
      : layer_(layer), name_(name), options_(options), cage_(cage) {}

  void run() {
    collect_reference_targets(layer_.root, 0);
    std::vector<std::pair<Composed, Matrix>> stack;
    // Root prims in reverse so that the stack pops them in file order.
    for (auto it = layer_.root.children.rbegin(); it != layer_.root.children.rend(); ++it) {
      const PrimSpec* root = it->get();
      const std::string path = "/" + root->name;
      if (reference_targets_.count(path)) continue;  // read where it is referenced
      Composed c{path, {}};
      expand(root, c, 0);
      stack.emplace_back(std::move(c), identity());
    }
    while (!stack.empty()) {
      auto [prim, parent] = std::move(stack.back());
      stack.pop_back();
      if (++visited_ > options_.limits.max_expanded_prims)
        throw InputError(name_, 0, "more than " + std::to_string(options_.limits.max_expanded_prims) +
                                       " prims once references and variants are expanded");
      bool defined = false, class_only = true;
      int active = -1;
      std::string type;
      for (const PrimSpec* s : prim.specs) {
        defined |= s->specifier == usd::Specifier::Def;
        class_only &= s->specifier == usd::Specifier::Class;
        if (type.empty()) type = s->type_name;
        if (active < 0) active = s->active;
        if (s->instanceable) note(s->line, "prim " + prim.path + " is instanceable: read as an ordinary prim");
        for (const std::string& r : s->external_references)
          note(s->line, "prim " + prim.path + ": " + printable(r, 80) + " is in another file, not read");
      }
      if (class_only) continue;
      (void)defined;
      if (active == 0) {
        note(prim.specs.front()->line, "prim " + prim.path + " is inactive (active = false): it and its children are not read");
        continue;
      }
      if (token(prim, "visibility", "inherited") == "invisible") {
        note(prim.specs.front()->line, "prim " + prim.path + " is invisible: it and its children are not read");
        continue;
      }
      const Matrix world = transform(prim, parent);
      if (type == "Mesh") read_mesh(prim, world);
      // Children, in order of first appearance; each child's specs in the parent's order.
      std::vector<std::string> names;
      for (const PrimSpec* s : prim.specs)
        for (const auto& c : s->children)
          if (std::find(names.begin(), names.end(), c->name) == names.end()) names.push_back(c->name);
      for (auto it = names.rbegin(); it != names.rend(); ++it) {
        Composed child{prim.path + "/" + *it, {}};
        if (reference_targets_.count(child.path)) continue;  // read where it is referenced
        for (const PrimSpec* s : prim.specs)
          if (const PrimSpec* c = s->child(*it)) expand(c, child, 0);
        stack.emplace_back(std::move(child), world);
      }
    }
    for (const auto& [set, variant] : options_.variants)
      if (!used_overrides_.count(set))
        throw InputError(name_, 0, "variant selection " + printable(set, 60) + "=" + printable(variant, 60) +
                                       ": the file has no variant set '" + printable(set, 60) + "' on the prims read" +
                                       variant_sets_text());
  }

 private:
  [[noreturn]] void fail(int line, const std::string& message) const { throw InputError(name_, line > 0 ? line : 0, message); }

  void note(int line, const std::string& message) {
    for (const Diagnostic& d : cage_.diagnostics)
      if (d.message == message) return;
    cage_.diagnostics.push_back(Diagnostic{"usd", ElementKind::None, line > 0 ? line : 0, message});
  }

  std::string variant_sets_text() const {
    std::string s;
    std::set<std::string> seen;
    for (const auto& v : cage_.usd.variant_sets)
      if (seen.insert(v.name).second) s += (s.empty() ? " (it has: " : ", ") + v.name;
    return s.empty() ? " (it has none)" : s + ")";
  }

  void collect_reference_targets(const PrimSpec& spec, int depth) {
    if (depth > options_.limits.max_depth) fail(0, "prims nest deeper than " + std::to_string(options_.limits.max_depth) + " levels");
    for (const std::string& r : spec.internal_references) reference_targets_.insert(r);
    for (const auto& c : spec.children) collect_reference_targets(*c, depth + 1);
    for (const auto& vs : spec.variant_sets)
      for (const auto& v : vs.variants) collect_reference_targets(*v.second, depth + 1);
  }

  const PrimSpec* find(const std::string& path) const {
    if (path.size() < 2 || path[0] != '/') return nullptr;
    const PrimSpec* spec = &layer_.root;
    std::size_t at = 1;
    while (at <= path.size()) {
      const std::size_t slash = std::min(path.find('/', at), path.size());
      spec = spec->child(path.substr(at, slash - at));
      if (!spec) return nullptr;
      at = slash + 1;
    }
    return spec;
  }

  /// Adds `spec`, its selected variants and its internal references (in that order of
  /// strength) to the composed prim.
  void expand(const PrimSpec* spec, Composed& prim, int depth) {
    if (depth > options_.limits.max_depth)
      fail(spec->line, "prim " + prim.path + ": variants and references nest deeper than " +
                           std::to_string(options_.limits.max_depth) + " levels (a reference cycle?)");
    if (++expansions_ > options_.limits.max_expanded_prims)
      fail(spec->line, "more than " + std::to_string(options_.limits.max_expanded_prims) + " prim specs once references and variants are expanded");
    prim.specs.push_back(spec);
    for (const usd::VariantSet& set : spec->variant_sets) {
      std::string selection;
      bool found = false;
      if (auto o = options_.variants.find(set.name); o != options_.variants.end()) {
        selection = o->second;
        found = true;
        used_overrides_.insert(set.name);
      }
      for (const PrimSpec* s : prim.specs) {
        if (found) break;
        if (auto it = s->variant_selection.find(set.name); it != s->variant_selection.end()) {
          selection = it->second;
          found = true;
        }
      }
      if (!found && !set.variants.empty()) selection = set.variants.front().first;
      record_variant_set(prim.path, set, selection);
      for (const auto& [variant, body] : set.variants)
        if (variant == selection) expand(body.get(), prim, depth + 1);
    }
    for (const std::string& target : spec->internal_references) {
      const PrimSpec* t = find(target);
      if (!t) {
        note(spec->line, "prim " + prim.path + " references <" + printable(target, 80) + ">, which the file does not define");
        continue;
      }
      if (std::find(reference_stack_.begin(), reference_stack_.end(), t) != reference_stack_.end())
        fail(spec->line, "prim " + prim.path + ": the reference to <" + printable(target, 80) + "> is cyclic");
      reference_stack_.push_back(t);
      expand(t, prim, depth + 1);
      reference_stack_.pop_back();
    }
  }

  void record_variant_set(const std::string& path, const usd::VariantSet& set, const std::string& selection) {
    auto& sets = cage_.usd.variant_sets;
    auto it = std::find_if(sets.begin(), sets.end(), [&](const auto& v) { return v.prim == path && v.name == set.name; });
    if (it == sets.end()) {
      sets.push_back({path, set.name, "", {}});
      it = sets.end() - 1;
    }
    for (const auto& v : set.variants) {
      if (std::find(it->variants.begin(), it->variants.end(), v.first) == it->variants.end()) it->variants.push_back(v.first);
      if (v.first == selection) it->selection = selection;
    }
    if (it->selection.empty() && selection.size() && set.variants.empty()) it->selection = selection;
  }

  /// The attribute's value: the strongest opinion's default, else its first time sample. Null
  /// when no spec has one (or the strongest blocks it).
  const Value* attribute(const Composed& prim, const std::string& name, int* line = nullptr) {
    for (const PrimSpec* s : prim.specs) {
      const Attribute* a = s->attribute(name);
      if (!a) continue;
      if (line) *line = a->line;
      if (a->has_default) return a->default_value.kind == Value::Kind::Empty && !a->default_value.array ? nullptr : &a->default_value;
      if (!a->samples.empty()) {
        const auto first = std::min_element(a->samples.begin(), a->samples.end(),
                                            [](const auto& x, const auto& y) { return x.first < y.first; });
        if (a->samples.size() > 1)
          note(a->line, "prim " + prim.path + ": '" + name + "' has " + std::to_string(a->samples.size()) +
                            " time samples; the first (time " + number_text(first->first) + ") is read");
        return &first->second;
      }
    }
    return nullptr;
  }

  std::string token(const Composed& prim, const std::string& name, const std::string& fallback) {
    int line = 0;
    const Value* v = attribute(prim, name, &line);
    if (!v) return fallback;
    if (v->kind != Value::Kind::Strings || v->strings.size() != 1) fail(line, "prim " + prim.path + ": '" + name + "' is not a token");
    return v->strings[0];
  }

  std::vector<double> numbers(const Composed& prim, const std::string& name, int& line, std::size_t width = 0) {
    line = 0;
    const Value* v = attribute(prim, name, &line);
    if (!v) return {};
    if (v->kind == Value::Kind::Strings) fail(line, "prim " + prim.path + ": '" + name + "' holds text, not numbers");
    if (width && v->numbers.size() % width != 0)
      fail(line, "prim " + prim.path + ": '" + name + "' has " + std::to_string(v->numbers.size()) + " numbers, not a multiple of " + std::to_string(width));
    return v->numbers;
  }

  std::vector<int> ints(const Composed& prim, const std::string& name, int& line) {
    const std::vector<double> x = numbers(prim, name, line);
    std::vector<int> out(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (!(x[i] == std::floor(x[i])) || std::abs(x[i]) > 2147483647.0)
        fail(line, "prim " + prim.path + ": '" + name + "' entry " + std::to_string(i) + " (" + number_text(x[i]) + ") is not an integer");
      out[i] = static_cast<int>(x[i]);
    }
    return out;
  }

  // --- transforms --------------------------------------------------------------------------

  Matrix op_matrix(const Composed& prim, std::string op) {
    bool invert = false;
    if (op.rfind("!invert!", 0) == 0) {
      invert = true;
      op = op.substr(8);
    }
    int line = 0;
    const Value* v = attribute(prim, op, &line);
    if (!v) fail(line, "prim " + prim.path + ": xformOpOrder names '" + printable(op, 60) + "', which has no value");
    if (v->kind != Value::Kind::Numbers) fail(line, "prim " + prim.path + ": '" + printable(op, 60) + "' is not numeric");
    const std::vector<double>& x = v->numbers;
    for (double d : x)
      if (!std::isfinite(d)) fail(line, "prim " + prim.path + ": '" + printable(op, 60) + "' is not finite");
    const std::string kind = op.substr(8, op.find(':', 8) == std::string::npos ? std::string::npos : op.find(':', 8) - 8);
    auto need = [&](std::size_t n) {
      if (x.size() != n) fail(line, "prim " + prim.path + ": '" + printable(op, 60) + "' has " + std::to_string(x.size()) + " values, not " + std::to_string(n));
    };
    Matrix m = identity();
    if (kind == "translate") {
      need(3);
      m[3] = x[0], m[7] = x[1], m[11] = x[2];
    } else if (kind == "scale") {
      need(3);
      m[0] = x[0], m[5] = x[1], m[10] = x[2];
    } else if (kind == "rotateX" || kind == "rotateY" || kind == "rotateZ") {
      need(1);
      m = rotation(kind[6] - 'X', x[0]);
    } else if (kind.size() == 9 && kind.rfind("rotate", 0) == 0) {  // rotateXYZ: X first, then Y, then Z
      need(3);
      for (int i = 0; i < 3; ++i) {
        const int axis = kind[6 + static_cast<std::size_t>(i)] - 'X';
        if (axis < 0 || axis > 2) fail(line, "prim " + prim.path + ": unknown xformOp '" + printable(op, 60) + "'");
        m = multiply(rotation(axis, x[static_cast<std::size_t>(axis)]), m);
      }
    } else if (kind == "orient") {  // quaternion, real part first
      need(4);
      const double n = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3]);
      if (!(n > 0)) fail(line, "prim " + prim.path + ": '" + printable(op, 60) + "' is a zero quaternion");
      const double w = x[0] / n, a = x[1] / n, b = x[2] / n, c = x[3] / n;
      m[0] = 1 - 2 * (b * b + c * c), m[1] = 2 * (a * b - c * w), m[2] = 2 * (a * c + b * w);
      m[4] = 2 * (a * b + c * w), m[5] = 1 - 2 * (a * a + c * c), m[6] = 2 * (b * c - a * w);
      m[8] = 2 * (a * c - b * w), m[9] = 2 * (b * c + a * w), m[10] = 1 - 2 * (a * a + b * b);
    } else if (kind == "transform") {  // USD's matrices act on row vectors: transpose
      need(16);
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m[r * 4 + c] = x[static_cast<std::size_t>(c * 4 + r)];
      if (m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1)
        fail(line, "prim " + prim.path + ": '" + printable(op, 60) + "' is a projective matrix (its last column is not 0 0 0 1)");
    } else {
      fail(line, "prim " + prim.path + ": unknown xformOp '" + printable(op, 60) + "'");
    }
    if (invert) {
      Matrix inverse;
      if (!invert_affine(m, inverse)) fail(line, "prim " + prim.path + ": '!invert!" + printable(op, 60) + "' is singular");
      m = inverse;
    }
    return m;
  }

  Matrix transform(const Composed& prim, const Matrix& parent) {
    int line = 0;
    const Value* order = attribute(prim, "xformOpOrder", &line);
    if (!order || order->strings.empty()) return parent;
    Matrix local = identity();
    bool reset = false;
    for (const std::string& op : order->strings) {
      if (op == "!resetXformStack!") {
        reset = true;
        local = identity();
        continue;
      }
      if (op.rfind("xformOp:", 0) != 0 && op.rfind("!invert!xformOp:", 0) != 0)
        fail(line, "prim " + prim.path + ": xformOpOrder names '" + printable(op, 60) + "', not an xformOp");
      local = multiply(local, op_matrix(prim, op));
    }
    return reset ? local : multiply(parent, local);
  }

  // --- meshes ------------------------------------------------------------------------------

  void read_mesh(const Composed& prim, const Matrix& world) {
    MeshInput& in = cage_.input;
    LoadedCage::UsdInfo::Mesh info;
    info.path = prim.path;
    int points_line = 0, counts_line = 0, indices_line = 0;
    const std::vector<double> points = numbers(prim, "points", points_line, 3);
    const std::vector<int> counts = ints(prim, "faceVertexCounts", counts_line);
    std::vector<int> indices = ints(prim, "faceVertexIndices", indices_line);
    const int line = prim.specs.front()->line;
    if (counts.empty()) {
      note(line, "Mesh " + prim.path + " has no faces: skipped");
      return;
    }
    const long n = static_cast<long>(points.size() / 3);
    long sum = 0;
    for (std::size_t f = 0; f < counts.size(); ++f) {
      if (counts[f] < 3)
        fail(counts_line, "Mesh " + prim.path + ": face " + std::to_string(f) + " has " + std::to_string(counts[f]) + " vertices (at least 3 needed)");
      sum += counts[f];
    }
    if (sum != static_cast<long>(indices.size()))
      fail(indices_line, "Mesh " + prim.path + ": faceVertexIndices has " + std::to_string(indices.size()) +
                             " entries, but faceVertexCounts adds up to " + std::to_string(sum));
    for (std::size_t i = 0; i < indices.size(); ++i)
      if (indices[i] < 0 || indices[i] >= n)
        fail(indices_line, "Mesh " + prim.path + ": faceVertexIndices entry " + std::to_string(i) + " is vertex " +
                               std::to_string(indices[i]) + ", but the mesh has " + std::to_string(n) + " points");
    if (static_cast<long>(in.positions.size()) + n > 2000000000L || in.face_indices.size() + indices.size() > 2000000000UL)
      fail(line, "the meshes together have more than 2e9 vertices or face corners");
    info.scheme = token(prim, "subdivisionScheme", "catmullClark");
    if (info.scheme == "bilinear" || info.scheme == "none")
      note(line, "Mesh " + prim.path + " has subdivisionScheme \"" + info.scheme +
                     "\" (a polygon mesh): read as a Catmull-Clark cage, so its surface is the smooth limit, not the flat polygons");
    else if (info.scheme == "loop")
      note(line, "Mesh " + prim.path + " has subdivisionScheme \"loop\": its triangles are read as a Catmull-Clark cage (a different surface)");
    else if (info.scheme != "catmullClark")
      fail(line, "Mesh " + prim.path + ": unknown subdivisionScheme '" + printable(info.scheme, 40) + "'");

    // Options: one set for the whole cage (the first mesh's).
    SubdivOptions options;
    const std::string boundary = token(prim, "interpolateBoundary", "edgeAndCorner");
    if (boundary == "none") options.boundary = BoundaryRule::None;
    else if (boundary == "edgeOnly") options.boundary = BoundaryRule::EdgeOnly;
    else if (boundary == "edgeAndCorner") options.boundary = BoundaryRule::EdgeAndCorner;
    else fail(line, "Mesh " + prim.path + ": interpolateBoundary '" + printable(boundary, 40) + "' is not none, edgeOnly or edgeAndCorner");
    const std::string triangles = token(prim, "triangleSubdivisionRule", "catmullClark");
    if (triangles == "smooth") options.triangles = TriangleRule::Smooth;
    else if (triangles != "catmullClark") fail(line, "Mesh " + prim.path + ": triangleSubdivisionRule '" + printable(triangles, 40) + "' is not catmullClark or smooth");
    if (cage_.usd.meshes.empty()) {
      in.options = options;
    } else if (options.boundary != in.options.boundary || options.triangles != in.options.triangles) {
      note(line, "Mesh " + prim.path + " has interpolateBoundary " + boundary + " / triangleSubdivisionRule " + triangles +
                     ", unlike the first mesh: the first mesh's rules apply to the whole cage");
    }

    const std::string orientation = token(prim, "orientation", "rightHanded");
    if (orientation != "rightHanded" && orientation != "leftHanded")
      fail(line, "Mesh " + prim.path + ": orientation '" + printable(orientation, 40) + "' is not rightHanded or leftHanded");
    const bool mirrored = determinant3(world) < 0;
    if (determinant3(world) == 0 || !std::isfinite(determinant3(world)))
      fail(line, "Mesh " + prim.path + ": its transform is singular (it flattens the mesh)");
    const bool reverse = (orientation == "leftHanded") != mirrored;

    const int v0 = static_cast<int>(in.positions.size()), f0 = static_cast<int>(in.face_sizes.size());
    for (long i = 0; i < n; ++i) {
      const double* p = &points[static_cast<std::size_t>(3 * i)];
      std::array<double, 3> q;
      for (int r = 0; r < 3; ++r) q[r] = world[r * 4] * p[0] + world[r * 4 + 1] * p[1] + world[r * 4 + 2] * p[2] + world[r * 4 + 3];
      for (double c : q)
        if (!std::isfinite(c)) fail(points_line, "Mesh " + prim.path + ": point " + std::to_string(i) + " is not finite");
      in.positions.push_back(q);
      cage_.vertex_line.push_back(points_line);
    }
    std::size_t at = 0;
    for (int c : counts) {
      in.face_sizes.push_back(c);
      if (reverse) std::reverse(indices.begin() + static_cast<std::ptrdiff_t>(at + 1), indices.begin() + static_cast<std::ptrdiff_t>(at + c));
      for (int k = 0; k < c; ++k) in.face_indices.push_back(indices[at + static_cast<std::size_t>(k)] + v0);
      at += static_cast<std::size_t>(c);
      cage_.face_line.push_back(counts_line);
    }

    // Creases: chains of creaseLengths vertices, one sharpness per crease or per edge.
    int crease_line = 0, lengths_line = 0, sharp_line = 0;
    const std::vector<int> crease = ints(prim, "creaseIndices", crease_line);
    const std::vector<int> lengths = ints(prim, "creaseLengths", lengths_line);
    const std::vector<double> sharpness = numbers(prim, "creaseSharpnesses", sharp_line);
    long crease_sum = 0, edges = 0;
    for (int l : lengths) {
      if (l < 2) fail(lengths_line, "Mesh " + prim.path + ": a crease of " + std::to_string(l) + " vertices (creaseLengths entries are at least 2)");
      crease_sum += l;
      edges += l - 1;
    }
    if (crease_sum != static_cast<long>(crease.size()))
      fail(crease_line ? crease_line : lengths_line, "Mesh " + prim.path + ": creaseIndices has " + std::to_string(crease.size()) +
                                                       " entries, but creaseLengths adds up to " + std::to_string(crease_sum));
    const bool per_crease = sharpness.size() == lengths.size();
    if (!lengths.empty() && !per_crease && static_cast<long>(sharpness.size()) != edges)
      fail(sharp_line ? sharp_line : lengths_line, "Mesh " + prim.path + ": creaseSharpnesses has " + std::to_string(sharpness.size()) +
                                                       " entries, neither one per crease (" + std::to_string(lengths.size()) +
                                                       ") nor one per edge (" + std::to_string(edges) + ")");
    for (int v : crease)
      if (v < 0 || v >= n) fail(crease_line, "Mesh " + prim.path + ": creaseIndices names vertex " + std::to_string(v) + ", but the mesh has " + std::to_string(n) + " points");
    std::size_t start = 0, edge = 0;
    for (std::size_t c = 0; c < lengths.size(); ++c) {
      for (int k = 0; k + 1 < lengths[c]; ++k, ++edge) {
        const double s = per_crease ? sharpness[c] : sharpness[edge];
        in.creases.push_back({crease[start + static_cast<std::size_t>(k)] + v0, crease[start + static_cast<std::size_t>(k) + 1] + v0, s});
        cage_.crease_line.push_back(sharp_line ? sharp_line : crease_line);
        ++info.creases;
      }
      start += static_cast<std::size_t>(lengths[c]);
    }

    int corner_line = 0, corner_sharp_line = 0;
    const std::vector<int> corners = ints(prim, "cornerIndices", corner_line);
    const std::vector<double> corner_sharpness = numbers(prim, "cornerSharpnesses", corner_sharp_line);
    if (corners.size() != corner_sharpness.size())
      fail(corner_line ? corner_line : corner_sharp_line, "Mesh " + prim.path + ": cornerIndices has " + std::to_string(corners.size()) +
                                                            " entries, cornerSharpnesses " + std::to_string(corner_sharpness.size()));
    for (std::size_t i = 0; i < corners.size(); ++i) {
      if (corners[i] < 0 || corners[i] >= n)
        fail(corner_line, "Mesh " + prim.path + ": cornerIndices names vertex " + std::to_string(corners[i]) + ", but the mesh has " + std::to_string(n) + " points");
      in.corners.push_back({corners[i] + v0, corner_sharpness[i]});
      cage_.corner_line.push_back(corner_sharp_line ? corner_sharp_line : corner_line);
      ++info.corners;
    }

    int hole_line = 0;
    for (int h : ints(prim, "holeIndices", hole_line)) {
      if (h < 0 || h >= static_cast<int>(counts.size()))
        fail(hole_line, "Mesh " + prim.path + ": holeIndices names face " + std::to_string(h) + ", but the mesh has " + std::to_string(counts.size()) + " faces");
      in.holes.push_back(h + f0);
      cage_.hole_line.push_back(hole_line);
      ++info.holes;
    }
    info.vertices = static_cast<int>(n);
    info.faces = static_cast<int>(counts.size());
    cage_.usd.meshes.push_back(info);
  }

  const Layer& layer_;
  const std::string& name_;
  const UsdReadOptions& options_;
  LoadedCage& cage_;
  std::set<std::string> reference_targets_;
  std::set<std::string> used_overrides_;
  std::vector<const PrimSpec*> reference_stack_;
  long visited_ = 0, expansions_ = 0;
};

}  // namespace

void add_variant_selection(UsdReadOptions& options, const std::string& text) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw Error(ErrorKind::Usage, "variant '" + printable(text, 80) + "' is not SET=NAME (e.g. geo=quad_creases)");
  options.variants[text.substr(0, eq)] = text.substr(eq + 1);
}

bool looks_like_usd(std::string_view bytes) {
  return bytes.substr(0, 5) == "#usda" || bytes.substr(0, 8) == "PXR-USDC";
}

LoadedCage parse_usd(const std::string& bytes, const std::string& name, const UsdReadOptions& options) {
  LoadedCage cage;
  cage.path = name;
  usd::Layer layer;
  std::string_view data = bytes;
  std::string prefix;
  if (data.substr(0, 4) == std::string_view("PK\x03\x04", 4)) {
    std::string entry;
    data = usdz_layer(data, name, entry);
    prefix = "usdz/";
    cage.diagnostics.push_back(Diagnostic{"usd", ElementKind::None, 0, "usdz: reading the layer '" + printable(entry, 80) + "'"});
  }
  if (data.substr(0, 8) == "PXR-USDC") {
    usd::parse_usdc(data, name, options.limits, layer);
  } else if (data.substr(0, 5) == "#usda") {
    usd::parse_usda(data, name, options.limits, layer);
  } else {
    throw InputError(name, 0, "not a USD file: it starts with neither '#usda' (text) nor 'PXR-USDC' (binary crate) nor a zip header (usdz)");
  }
  cage.usd.applied = true;
  cage.usd.encoding = prefix + layer.encoding;
  cage.usd.version = layer.version;
  cage.usd.meters_per_unit = layer.meters_per_unit;
  cage.usd.up_axis = layer.up_axis;
  for (const std::string& n : layer.notes) cage.diagnostics.push_back(Diagnostic{"usd", ElementKind::None, 0, n});
  Reader(layer, name, options, cage).run();
  if (layer.encoding == "usdc") {  // no lines: messages name the cage's vertex or face
    cage.locator = LoadedCage::Locator::Element;
    for (std::size_t i = 0; i < cage.vertex_line.size(); ++i) cage.vertex_line[i] = static_cast<int>(i + 1);
    for (std::size_t i = 0; i < cage.face_line.size(); ++i) cage.face_line[i] = static_cast<int>(i + 1);
  }
  if (cage.usd.meshes.empty())
    throw InputError(name, 0, "the USD file has no Mesh prim with faces (looked through " +
                                  std::string(cage.usd.variant_sets.empty() ? "every prim" : "every prim, with the variants selected") + ")");
  return cage;
}

LoadedCage read_usd(const std::string& path, const UsdReadOptions& options) {
  return parse_usd(read_input_file(path, "a USD file"), path, options);
}

}  // namespace subd2nurbs
