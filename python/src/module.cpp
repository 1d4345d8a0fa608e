// _subd2nurbs: the compiled part of the Python package `subd2nurbs` (python/subd2nurbs/).
// Thin: it turns plain arrays into a MeshInput, runs the same code as the CLI (io/obj_reader,
// core, converter/pipeline) and hands back plain Python data (dicts, lists, numpy arrays), or,
// for a conversion, bound objects: Settings (the keyword arguments as ConversionSettings) and
// Conversion (the result, with the B-rep kept as the OCCT shape).
// The package validates arguments before calling in here; errors raised here are the
// package's exception classes (subd2nurbs.errors), created by the translator below.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Standard_Version.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>

#include <array>
#include <memory>
#include <new>
#include <numeric>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "converter/occt/export_error.h"
#include "converter/occt/shape_check.h"
#include "converter/occt/writers.h"
#include "converter/pipeline/conversion.h"
#include "converter/pipeline/errors.h"
#include "converter/pipeline/input.h"
#include "converter/pipeline/report.h"
#include "converter/pipeline/settings.h"
#include "converter/pipeline/shape_fit_report.h"
#include "core/analysis/mesh_stats.h"
#include "core/eval/preview_mesh.h"
#include "core/fit/fairing.h"
#include "core/fit/interpolate.h"
#include "core/limit/limit_evaluator.h"
#include "core/mesh/errors.h"
#include "core/refine/refiner.h"
#include "core/util/parallel.h"
#include "core/mesh/quad_recovery.h"
#include "io/cage_reader.h"
#include "io/input_error.h"
#include "io/obj_reader.h"
#include "io/target_reader.h"

namespace py = pybind11;
using namespace subd2nurbs;

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IntArray = py::array_t<int, py::array::c_style | py::array::forcecast>;

/// Sets items of `d` from (key, value) pairs: set_items(d, "a", 1, "b", 2.5).
template <class Value, class... Rest>
void set_items(py::dict& d, const char* key, const Value& value, const Rest&... rest) {
  d[key] = value;
  if constexpr (sizeof...(rest) > 0) set_items(d, rest...);
}

/// f() run without the interpreter lock, so that other Python threads run meanwhile and several
/// threads convert in parallel (#32 item 5). f must not touch Python objects; an exception
/// from f propagates with the lock taken back.
template <class F>
auto without_gil(F&& f) {
  py::gil_scoped_release unlocked;
  return f();
}

// --- errors ---------------------------------------------------------------------------------

const char* element_name(ElementKind k) {
  switch (k) {
    case ElementKind::None: return "";
    case ElementKind::Vertex: return "vertex";
    case ElementKind::Face: return "face";
    case ElementKind::Edge: return "edge";
    case ElementKind::Tag: return "tag";
  }
  return "";
}

/// Raises subd2nurbs.errors.<name>(message, **attributes), the attributes as (name, value) pairs.
template <class... Attributes>
void raise(const char* name, const std::string& message, const Attributes&... attributes) {
  py::dict a;
  if constexpr (sizeof...(attributes) > 0) set_items(a, attributes...);
  py::object cls = py::module_::import("subd2nurbs.errors").attr(name);
  py::object error = cls(message, **a);
  PyErr_SetObject(cls.ptr(), error.ptr());
}

/// Thrown from a conversion's progress callback when the Python callable returned False.
struct CancelledByProgress {};

/// Raises the Python exception of an error's kind (converter/pipeline/errors.h) with the
/// attributes its class carries.
void translate(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const Error& e) {
    const char* cls = pipeline::error_class(e.kind()).python;
    if (const auto* m = dynamic_cast<const InvalidMeshError*>(&e))
      raise(cls, e.what(), "code", to_string(m->code()), "element", element_name(m->element()), "index", m->index(),
            "index2", m->index2());
    else if (const auto* i = dynamic_cast<const InputError*>(&e))
      raise(cls, e.what(), "file", i->file(), "line", i->line(), "code",
            i->code() ? py::object(py::str(to_string(*i->code()))) : py::object(py::none()));
    else if (const auto* w = dynamic_cast<const WriteError*>(&e))
      raise(cls, e.what(), "file", w->file());
    else if (const auto* s = dynamic_cast<const pipeline::SettingsError*>(&e))
      raise(cls, e.what(), "setting", s->setting(), "rule", s->rule());
    else if (const auto* f = dynamic_cast<const FitError*>(&e))
      raise(cls, e.what(), "vertices", f->vertices());
    else if (e.kind() == ErrorKind::Resources)
      raise(cls, e.what(), "code", "resource-limit");
    else if (const auto* x = dynamic_cast<const occt::ExportError*>(&e))
      raise(cls, e.what(), "stage", x->stage, "patch", x->patch);
    else
      raise(cls, e.what());
  } catch (const std::bad_alloc&) {
    PyErr_SetString(PyExc_MemoryError, "out of memory");
  } catch (const std::invalid_argument& e) {
    // A broken precondition of the core: a bug, not the user's error.
    raise("ConversionError", std::string("internal error: ") + e.what(), "stage", "internal");
  }
}

// --- cages ----------------------------------------------------------------------------------

/// The options as the package passes them ({boundary, crease_method, triangles}, each optional),
/// checked by the converter's rules.
SubdivOptions subdiv_options(const py::dict& options) {
  SubdivOptions o;
  auto name = [&](const char* key) { return std::string(py::str(options[key])); };
  if (options.contains("boundary")) o.boundary = pipeline::boundary_rule(name("boundary"));
  if (options.contains("crease_method")) o.crease_method = pipeline::crease_method(name("crease_method"));
  if (options.contains("triangles")) o.triangles = pipeline::triangle_rule(name("triangles"));
  return o;
}

/// A cage as the package passes it: (positions Nx3, face_sizes, face_indices,
/// creases [(a, b, s)], corners [(v, s)], holes [f], options {boundary, crease_method, triangles}).
MeshInput make_input(const DoubleArray& positions, const IntArray& face_sizes, const IntArray& face_indices,
                     const std::vector<std::tuple<int, int, double>>& creases,
                     const std::vector<std::pair<int, double>>& corners, const std::vector<int>& holes,
                     const py::dict& options) {
  if (positions.ndim() != 2 || positions.shape(1) != 3)
    throw pipeline::SettingsError("vertices", "must be an array of shape (n, 3)");
  MeshInput in;
  const double* p = positions.data();
  in.positions.resize(static_cast<size_t>(positions.shape(0)));
  for (size_t i = 0; i < in.positions.size(); ++i) in.positions[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
  in.face_sizes.assign(face_sizes.data(), face_sizes.data() + face_sizes.size());
  in.face_indices.assign(face_indices.data(), face_indices.data() + face_indices.size());
  for (const auto& [a, b, s] : creases) in.creases.push_back({a, b, s});
  for (const auto& [v, s] : corners) in.corners.push_back({v, s});
  in.holes = holes;
  in.options = subdiv_options(options);
  return in;
}

py::array_t<double> points_array(const std::vector<Point3>& points) {
  py::array_t<double> a({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  auto m = a.mutable_unchecked<2>();
  for (size_t i = 0; i < points.size(); ++i)
    for (int k = 0; k < 3; ++k) m(static_cast<py::ssize_t>(i), k) = points[i][k];
  return a;
}

template <class Ints>
py::array_t<int> int_array(const Ints& v) {
  py::array_t<int> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

py::dict cage_dict(const MeshInput& in) {
  py::dict d;
  set_items(d, "vertices", points_array(std::vector<Point3>(in.positions.begin(), in.positions.end())),
               "face_sizes", int_array(in.face_sizes), "face_indices", int_array(in.face_indices));
  py::list creases, corners;
  for (const CreaseTag& c : in.creases) creases.append(py::make_tuple(c.v0, c.v1, c.sharpness));
  for (const CornerTag& c : in.corners) corners.append(py::make_tuple(c.vertex, c.sharpness));
  set_items(d, "creases", creases, "corners", corners, "holes", in.holes);
  py::dict o;
  set_items(o, "boundary", to_string(in.options.boundary), "crease_method", to_string(in.options.crease_method),
               "triangles", to_string(in.options.triangles));
  d["options"] = o;
  return d;
}

std::vector<std::string> diagnostics_text(const Diagnostics& diagnostics) {
  std::vector<std::string> out;
  for (const Diagnostic& d : diagnostics) {
    std::string where = element_name(d.element);
    out.push_back((where.empty() ? std::string() : where + " " + std::to_string(d.index) + ": ") + d.message);
  }
  return out;
}

py::dict recovery_dict(const LoadedCage::QuadRecovery& q) {
  py::dict d;
  set_items(d, "source_triangles", q.source_triangles, "quads", q.quads, "triangles_kept", q.triangles_kept,
               "fan_vertices", q.fan_vertices);
  return d;
}

/// Reads and validates a cage as every front end does (pipeline::load_input): any format
/// read_cage reads, errors naming the file and line, the warnings as text.
/// `input`: auto, mesh or cage (pipeline/mesh_path.h); `variants`: USD variant selections
/// "SET=NAME" (io/usd_reader.h).
py::dict read_cage_file(const std::string& path, const std::string& input, const std::vector<std::string>& variants) {
  UsdReadOptions usd;
  for (const std::string& v : variants) add_variant_selection(usd, v);
  pipeline::LoadedSource source = pipeline::load_source(path, pipeline::input_kind(input), usd);
  py::dict route;
  set_items(route, "kind", source.route.mesh ? "mesh" : "cage", "reason", source.route.reason);
  if (source.route.mesh) {  // the mesh's faces as in the file: convert() remeshes them
    py::dict d = cage_dict(source.mesh.input);
    set_items(d, "warnings", source.warnings, "path", path, "quad_recovery", py::none(), "route", route, "usd",
              py::none());
    return d;
  }
  const pipeline::LoadedInput& loaded = *source.cage;
  const LoadedCage& cage = loaded.cage;
  py::dict d = cage_dict(cage.input);
  set_items(d, "warnings", loaded.warnings, "path", path, "quad_recovery",
            cage.recovery.applied ? py::object(recovery_dict(cage.recovery)) : py::object(py::none()), "route", route);
  py::object usd_info = py::none();
  if (cage.usd.applied) {
    py::dict u;
    py::list meshes, sets;
    for (const auto& m : cage.usd.meshes) {
      py::dict md;
      set_items(md, "path", m.path, "scheme", m.scheme, "vertices", m.vertices, "faces", m.faces, "crease_edges",
                m.creases, "corners", m.corners, "holes", m.holes);
      meshes.append(md);
    }
    for (const auto& v : cage.usd.variant_sets) {
      py::dict vd;
      set_items(vd, "prim", v.prim, "name", v.name, "selection", v.selection, "variants", v.variants);
      sets.append(vd);
    }
    set_items(u, "encoding", cage.usd.encoding, "version", cage.usd.version, "meters_per_unit",
              cage.usd.meters_per_unit, "up_axis", cage.usd.up_axis, "meshes", meshes, "variant_sets", sets);
    usd_info = u;
  }
  d["usd"] = usd_info;
  return d;
}

/// Pairs triangles into quads (core/mesh/quad_recovery.h): (cage dict, counts, sources).
py::tuple recover_quads_from(const DoubleArray& positions, const IntArray& face_sizes, const IntArray& face_indices,
                             const std::vector<std::tuple<int, int, double>>& creases,
                             const std::vector<std::pair<int, double>>& corners, const std::vector<int>& holes,
                             const py::dict& options) {
  const MeshInput in = make_input(positions, face_sizes, face_indices, creases, corners, holes, options);
  const QuadRecoveryResult r = recover_quads(in);
  py::dict counts;
  set_items(counts, "source_triangles", r.input_triangles, "quads", r.quads, "triangles_kept", r.triangles_kept,
                    "fan_vertices", r.fan_vertices, "fan_triangles", r.fan_triangles, "other_faces", r.other_faces);
  return py::make_tuple(cage_dict(r.mesh), counts, r.sources);
}

/// Validates a cage given as arrays: the warnings (unused vertices, ...) as text.
std::vector<std::string> validate(const DoubleArray& positions, const IntArray& face_sizes,
                                  const IntArray& face_indices,
                                  const std::vector<std::tuple<int, int, double>>& creases,
                                  const std::vector<std::pair<int, double>>& corners,
                                  const std::vector<int>& holes, const py::dict& options) {
  const MeshInput in = make_input(positions, face_sizes, face_indices, creases, corners, holes, options);
  Diagnostics diagnostics;
  SubdivLevel::from_input(in, &diagnostics);
  return diagnostics_text(diagnostics);
}

py::dict info(const DoubleArray& positions, const IntArray& face_sizes, const IntArray& face_indices,
              const std::vector<std::tuple<int, int, double>>& creases,
              const std::vector<std::pair<int, double>>& corners, const std::vector<int>& holes,
              const py::dict& options) {
  const MeshInput in = make_input(positions, face_sizes, face_indices, creases, corners, holes, options);
  Diagnostics diagnostics;
  const SubdivLevel level = SubdivLevel::from_input(in, &diagnostics);
  const MeshStats s = compute_stats(level, std::vector<Point3>(in.positions.begin(), in.positions.end()));
  py::dict d;
  set_items(d, "vertices", s.vertices, "faces", s.faces, "edges", s.edges, "corners", s.corners,
               "face_sizes", s.face_sizes, "valences", s.valences, "boundary_edges", s.boundary_edges,
               "boundary_vertices", s.boundary_vertices, "boundary_loops", s.boundary_loops,
               "infinite_crease_edges", s.infinite_crease_edges,
               "semi_sharp_crease_edges", s.semi_sharp_crease_edges, "corner_vertices", s.corner_vertices,
               "topological_corners", s.topological_corners, "holes", s.holes,
               "extraordinary_vertices", s.extraordinary_vertices, "unused_vertices", s.unused_vertices,
               "components", s.components, "euler_characteristic", s.euler_characteristic, "closed", s.closed);
  py::dict b;
  set_items(b, "min", std::vector<double>(s.bounds.min.begin(), s.bounds.min.end()),
               "max", std::vector<double>(s.bounds.max.begin(), s.bounds.max.end()), "diagonal", s.bounds.diagonal);
  d["bounds"] = b;
  d["warnings"] = diagnostics_text(diagnostics);
  return d;
}

/// The limits as the package passes them (None: the default; max_memory a number of bytes or a
/// size string), checked by the pipeline's rules.
pipeline::ResourceLimits resource_limits(std::optional<double> max_faces, const py::object& max_memory) {
  pipeline::ResourceLimits limits;
  limits.max_faces = max_faces;
  if (py::isinstance<py::str>(max_memory))
    limits.max_memory = pipeline::memory_size(max_memory.cast<std::string>());
  else if (!max_memory.is_none())
    limits.max_memory = max_memory.cast<double>();
  pipeline::validate(limits);
  return limits;
}

py::tuple refine(const DoubleArray& positions, const IntArray& face_sizes, const IntArray& face_indices,
                 const std::vector<std::tuple<int, int, double>>& creases,
                 const std::vector<std::pair<int, double>>& corners, const std::vector<int>& holes,
                 const py::dict& options, int levels, std::optional<double> max_faces, const py::object& max_memory) {
  pipeline::check_refine_levels(levels);
  const pipeline::ResourceLimits limits = resource_limits(max_faces, max_memory);
  const MeshInput in = make_input(positions, face_sizes, face_indices, creases, corners, holes, options);
  const SubdivLevel base = SubdivLevel::from_input(in);
  pipeline::check_resources(pipeline::estimate_refinement(base, levels), limits, pipeline::kDefaultMaxRefineFaces,
                            "refining " + std::to_string(base.mesh.num_faces()) + " faces to level " +
                                std::to_string(levels),
                            "use fewer levels");
  const auto [r, last] = without_gil([&] {
    Refinement refined = refine_uniform(base, levels);
    std::vector<Point3> x = refined.positions(std::vector<Point3>(in.positions.begin(), in.positions.end())).back();
    return std::make_pair(std::move(refined), std::move(x));
  });
  const PolyMesh& m = r.levels.back().mesh;
  std::vector<int> sizes(static_cast<size_t>(m.num_faces())), indices;
  indices.reserve(static_cast<size_t>(m.num_corners()));
  for (int f = 0; f < m.num_faces(); ++f) {
    sizes[static_cast<size_t>(f)] = m.face_size(f);
    indices.insert(indices.end(), m.face_vertices(f), m.face_vertices(f) + m.face_size(f));
  }
  return py::make_tuple(points_array(last), int_array(sizes), int_array(indices));
}

// --- conversion -----------------------------------------------------------------------------

py::dict knots_dict(const KnotVector& k) {
  py::dict d;
  d["knots"] = py::array_t<double>(static_cast<py::ssize_t>(k.knots.size()), k.knots.data());
  d["mults"] = int_array(k.mults);
  return d;
}

py::dict patch_dict(const NurbsPatch& p) {
  py::dict d;
  d["degree_u"] = p.degree_u;
  d["degree_v"] = p.degree_v;
  const py::dict ku = knots_dict(p.knots_u), kv = knots_dict(p.knots_v);
  set_items(d, "knots_u", ku["knots"], "mults_u", ku["mults"], "knots_v", kv["knots"], "mults_v", kv["mults"]);
  py::array_t<double> poles({static_cast<py::ssize_t>(p.num_poles_u), static_cast<py::ssize_t>(p.num_poles_v),
                             py::ssize_t{3}});
  auto m = poles.mutable_unchecked<3>();
  for (int i = 0; i < p.num_poles_u; ++i)
    for (int j = 0; j < p.num_poles_v; ++j)
      for (int k = 0; k < 3; ++k) m(i, j, k) = p.pole(i, j)[k];
  d["poles"] = poles;
  if (p.weights.empty()) {
    d["weights"] = py::none();
  } else {
    py::array_t<double> w({static_cast<py::ssize_t>(p.num_poles_u), static_cast<py::ssize_t>(p.num_poles_v)});
    std::copy(p.weights.begin(), p.weights.end(), w.mutable_data());
    d["weights"] = w;
  }
  d["base_faces"] = std::vector<int>(p.base_faces.begin(), p.base_faces.end());  // a list
  if (p.cells.empty()) {
    d["cells"] = py::none();
  } else {  // a packed face: one row (base_face, coarse_face, u, v, rotation) per coarse quad
    py::array_t<int> cells({static_cast<py::ssize_t>(p.cells.size()), py::ssize_t{5}});
    auto c = cells.mutable_unchecked<2>();
    for (size_t i = 0; i < p.cells.size(); ++i) {
      const PatchCell& q = p.cells[i];
      const int row[5] = {q.base_face, q.coarse_face, q.u, q.v, q.rotation};
      for (int k = 0; k < 5; ++k) c(static_cast<py::ssize_t>(i), k) = row[k];
    }
    d["cells"] = cells;
  }
  return d;
}

// --- settings: the keyword arguments of subd2nurbs.convert, by the settings table -----------

/// A keyword's value as its row's type (the package checked the Python types; None: not given).
pipeline::SettingValue setting_value(const pipeline::SettingRow& row, const py::handle v) {
  using pipeline::SettingType;
  if (v.is_none()) return std::monostate{};
  switch (row.type) {
    case SettingType::Flag: return v.cast<bool>();
    case SettingType::Integer: return v.cast<long long>();
    case SettingType::Number: return v.cast<double>();
    case SettingType::Word: return v.cast<std::string>();
    case SettingType::OnOff:  // True / False, or the command line's "on" / "off"
      if (py::isinstance<py::str>(v)) return v.cast<std::string>();
      return v.cast<bool>();
    case SettingType::Size:  // bytes, or a size string such as "8G"
      if (py::isinstance<py::str>(v)) return v.cast<std::string>();
      return v.cast<double>();
  }
  return std::monostate{};
}

py::object python_value(const pipeline::SettingValue& v) {
  if (const auto* b = std::get_if<bool>(&v)) return py::bool_(*b);
  if (const auto* i = std::get_if<long long>(&v)) return py::int_(*i);
  if (const auto* x = std::get_if<double>(&v)) return py::float_(*x);
  if (const auto* t = std::get_if<std::string>(&v)) return py::str(*t);
  return py::none();
}

/// The settings of a conversion: convert's keyword arguments mapped onto pipeline::Settings by
/// the settings table and checked by the pipeline's rules when the object is made.
struct Settings {
  pipeline::Settings settings;
};

Settings make_settings(const py::kwargs& kwargs) {
  std::vector<std::pair<std::string, pipeline::SettingValue>> given;
  for (const auto& item : kwargs) {
    const std::string name = py::str(item.first);
    const pipeline::SettingRow* row = pipeline::find_setting(name);
    if (!row || !row->python) throw py::type_error("Settings: unknown setting '" + name + "'");
    given.emplace_back(name, setting_value(*row, item.second));
  }
  return Settings{pipeline::make_settings(given)};
}

/// The table as Python data: one dict per row the Python module offers (name, type, default,
/// default_text, help, choices, cli, property {name, group, tooltip, choices, zero_is_default,
/// scale} or None).
py::list settings_table() {
  py::list rows;
  for (const pipeline::SettingRow& r : pipeline::settings_table()) {
    py::dict d;
    set_items(d, "name", r.name, "type", pipeline::to_string(r.type), "default", python_value(r.default_value),
                 "default_text", r.default_text, "help", r.help, "choices", r.choices,
                 "cli", r.cli.empty() ? py::object(py::none()) : py::object(py::str(r.cli)), "python", r.python);
    if (r.property.name.empty()) {
      d["property"] = py::none();
    } else {
      py::dict p;
      py::list choices;
      for (const auto& [shown, name] : r.property.choices) choices.append(py::make_tuple(shown, name));
      set_items(p, "name", r.property.name, "group", r.property.group,
                   "tooltip", r.property.tooltip.empty() ? r.help : r.property.tooltip, "choices", choices,
                   "zero_is_default", r.property.zero_is_default, "scale", r.property.scale);
      d["property"] = p;
    }
    rows.append(d);
  }
  return rows;
}

py::dict preview_dict(const PreviewMesh& mesh, const std::string& color) {
  const auto n = static_cast<py::ssize_t>(mesh.values.size());
  auto rows = [&](const std::vector<float>& v) { return py::array_t<float>({n, static_cast<py::ssize_t>(3)}, v.data()); };
  py::dict pv;
  set_items(pv, "positions", rows(mesh.positions), "normals", rows(mesh.normals), "colors", rows(mesh.colors),
                "values", py::array_t<float>(n, mesh.values.data()));
  pv["triangles"] = py::array_t<std::uint32_t>({static_cast<py::ssize_t>(mesh.indices.size() / 3), static_cast<py::ssize_t>(3)},
                                              mesh.indices.data());
  set_items(pv, "value_min", mesh.value_min, "value_max", mesh.value_max, "color", color);
  return pv;
}

/// A conversion as the package keeps it: the pipeline's result with the cage it came from (for
/// previews made later) and the B-rep as the OCCT shape; its parts become Python data when asked.
struct Conversion {
  std::shared_ptr<const SubdivLevel> base;
  pipeline::ConversionResult result;
  std::optional<MeshInput> cage_input;  ///< a mesh input: the cage made from it (positions: as remeshed)

  /// A mesh input: the cage made from it, fitted (a cage dict), else None.
  py::object made_cage() const {
    if (!cage_input) return py::none();
    MeshInput fitted = *cage_input;
    for (std::size_t i = 0; i < fitted.positions.size() && i < result.cage.size(); ++i) fitted.positions[i] = result.cage[i];
    return cage_dict(fitted);
  }
  std::optional<std::string> brep_text;  ///< made on first use

  py::object text() {
    if (!result.has_brep) return py::none();
    if (!brep_text) {
      std::string made = without_gil([&] { return occt::brep_text(result.brep.shape); });
      if (!brep_text) brep_text = std::move(made);  // with the lock: another thread may have made it
    }
    return py::str(*brep_text);
  }

  py::list patches() const {
    py::list list;
    for (const NurbsPatch& p : result.exported.set.patches) list.append(patch_dict(p));
    return list;
  }

  py::list diagnostics() const {
    py::list list;
    for (const pipeline::ConversionDiagnostic& x : result.diagnostics) {
      py::dict e;
      set_items(e, "severity", pipeline::to_string(x.severity), "code", pipeline::to_string(x.code),
                   "message", x.message, "element", x.element,
                   "remedy", x.remedy.empty() ? py::object(py::none()) : py::object(py::str(x.remedy)));
      list.append(e);
    }
    return list;
  }

  /// Per shared curve: its measures, and the B-rep edge it became (1-based index in
  /// TopExp::MapShapes order, which is FreeCAD's Shape.Edges order; 0 when none).
  py::dict curve_measures() const {
    const pipeline::ConversionResult& c = result;
    const auto& curves = c.continuity.curves;
    std::vector<int> curve(curves.size()), claimed(curves.size()), edge(curves.size(), 0);
    std::vector<double> gap(curves.size()), angle(curves.size());
    TopTools_IndexedMapOfShape edge_map;
    if (c.has_brep && !c.brep.shape.IsNull()) TopExp::MapShapes(c.brep.shape, TopAbs_EDGE, edge_map);
    for (size_t i = 0; i < curves.size(); ++i) {
      curve[i] = curves[i].curve;
      claimed[i] = static_cast<int>(curves[i].claimed);
      gap[i] = curves[i].gap;
      angle[i] = curves[i].normal_angle_deg;
      if (c.has_brep && curve[i] >= 0 && static_cast<size_t>(curve[i]) < c.brep.curve_edges.size() &&
          !c.brep.curve_edges[curve[i]].IsNull())
        edge[i] = edge_map.FindIndex(c.brep.curve_edges[curve[i]]);
    }
    py::dict m;
    set_items(m, "curve", int_array(curve), "claimed", int_array(claimed),
                 "gap", py::array_t<double>(static_cast<py::ssize_t>(gap.size()), gap.data()),
                 "normal_angle_deg", py::array_t<double>(static_cast<py::ssize_t>(angle.size()), angle.data()),
                 "edge", int_array(edge));
    return m;
  }

  py::object brep() const {
    if (!result.has_brep) return py::none();
    const occt::BrepResult& r = result.brep;
    py::dict b;
    set_items(b, "valid", r.valid, "is_solid", r.is_solid, "faces", r.num_faces, "edges", r.num_edges,
                 "vertices", r.num_vertices, "solids", r.num_solids, "shells", r.num_shells,
                 "check_message", r.check_message, "tolerance", r.tolerance, "planar_faces", r.planar_faces,
                 "merged_patches", r.merged_patches, "folded_planar_patches", r.folded_planar_patches);
    return std::move(b);
  }

  py::object preview() const {
    if (!result.preview) return py::none();
    return preview_dict(*result.preview, to_string(result.preview_settings.color));
  }

  /// The preview stage on this result's patches (as convert(preview=...) makes it).
  py::dict make_preview(const std::string& color, int samples) const {
    const pipeline::PreviewSettings settings{pipeline::preview_color(color), samples};
    return preview_dict(pipeline::build_preview(*base, result, settings), color);
  }

  /// Writes the shape as STEP / IGES / BREP (by extension), atomically, as the CLI does.
  void write(const std::string& path, const std::string& schema) const {
    const occt::StepSchema step = pipeline::step_schema(schema);
    occt::Format format;
    try {
      format = occt::format_from_path(path);
    } catch (const std::invalid_argument&) {
      throw pipeline::SettingsError("path", "must end in .step, .stp, .iges, .igs or .brep: '" + path + "'");
    }
    pipeline::check_exchange_output(result, result.input, format != occt::Format::Brep);
    without_gil([&] { occt::write_shape(result.brep.shape, path, format, step); });
  }
};

std::shared_ptr<Conversion> convert(const DoubleArray& positions, const IntArray& face_sizes, const IntArray& face_indices,
                                    const std::vector<std::tuple<int, int, double>>& creases,
                                    const std::vector<std::pair<int, double>>& corners, const std::vector<int>& holes,
                                    const py::dict& options, const Settings& settings, const std::string& input_name,
                                    const std::optional<std::vector<std::string>>& load_warnings,
                                    const std::function<py::object(const std::string&, double, const std::string&)>& progress) {
  const MeshInput in = make_input(positions, face_sizes, face_indices, creases, corners, holes, options);
  Diagnostics diagnostics;
  auto conversion = std::make_shared<Conversion>();
  std::vector<Point3> points(in.positions.begin(), in.positions.end());
  // The mesh path (pipeline/mesh_path.h): the road by the same rule as the command line's, the
  // cage's name standing for the file (read_cage keeps a mesh file's triangles).
  LoadedCage probe;
  probe.input = in;
  probe.path = input_name;
  const pipeline::InputRoute route = pipeline::route_input(probe, input_name, settings.settings.mesh.input);

  // The conversion runs without_gil; the progress callback takes the lock back for each call.
  // When it returns False the conversion stops at that call (an exception through the stages,
  // or the mesh path's own cancel) and subd2nurbs.Cancelled is raised: nothing is returned.
  pipeline::ConversionProgress callbacks;
  std::string current, key;
  bool cancelled = false;
  const auto report = [&](double fraction) {
    py::gil_scoped_acquire locked;
    const py::object go = progress(current, fraction, key);
    if (go.ptr() == Py_False) {
      cancelled = true;
      throw CancelledByProgress{};
    }
  };
  if (progress) {
    callbacks.stage = [&](pipeline::Stage stage, const std::string& s) {
      current = s;
      key = pipeline::to_string(stage);
      report(0.0);
    };
    callbacks.brep_fraction = report;
  }
  pipeline::ConversionResult& c = conversion->result;
  std::optional<pipeline::MeshPathReport> made;
  try {
    without_gil([&] {
      // threads= for the mesh path too (pipeline::convert sets it for itself)
      const ThreadLimit threads(settings.settings.conversion.limits.threads.value_or(0));
      const JobShare job;  // Python threads converting at once share the cores
      if (route.mesh) {
        pipeline::MeshPathProgress mesh_progress;
        if (progress) {
          mesh_progress.stage = [&](const std::string& s) {
            current = s;
            key = "mesh";
            report(0.0);
          };
          // The remesh's and the fit's fractions; a cancel there ends mesh_to_cage with its own error.
          mesh_progress.fraction = [&](double fraction) {
            try {
              report(fraction);
              return true;
            } catch (const CancelledByProgress&) {
              return false;
            }
          };
        }
        pipeline::MeshCage cage = pipeline::mesh_to_cage(probe, settings.settings.mesh, mesh_progress);
        cage.report.route = route;
        conversion->base = std::make_shared<const SubdivLevel>(std::move(cage.cage.level));
        conversion->cage_input = std::move(cage.cage.cage.input);
        points = std::move(cage.positions);
        made = std::move(cage.report);
      } else {
        conversion->base = std::make_shared<const SubdivLevel>(SubdivLevel::from_input(in, &diagnostics));
      }
      std::vector<std::string> warnings = load_warnings ? *load_warnings : diagnostics_text(diagnostics);
      if (made) warnings.insert(warnings.end(), made->warnings.begin(), made->warnings.end());  // tolerance not met, a fold
      c = pipeline::convert(*conversion->base, points, pipeline::conversion_settings(settings.settings), callbacks,
                            warnings);
    });
  } catch (const CancelledByProgress&) {  // a stage's callback: cancelled is set
  } catch (const Error&) {
    if (!cancelled) throw;  // else the mesh path's own "cancelled", after the callback's False
  }
  if (cancelled) {
    raise("Cancelled", "the conversion was cancelled (the progress callback returned False)");
    throw py::error_already_set();
  }
  c.mesh = std::move(made);
  c.input = input_name;
  if (c.has_brep) c.output.format = "BREP";
  return conversion;
}

/// Fairs a cage (as `subd2nurbs fair`): the free vertices minimise the thin-plate (+ membrane)
/// energy, the limit points stay close to where they were; kept vertices are copied.
py::dict fair_cage(const DoubleArray& positions, const IntArray& face_sizes, const IntArray& face_indices,
                   const std::vector<std::tuple<int, int, double>>& creases,
                   const std::vector<std::pair<int, double>>& corners, const std::vector<int>& holes,
                   const py::dict& options, double weight, const std::vector<std::string>& keep, int levels,
                   double membrane) {
  FairOptions fo;
  fo.weight = weight;
  fo.energy.levels = levels;
  fo.energy.membrane = membrane;
  pipeline::validate_fairing(fo.weight, fo.energy);
  const KeepSet ks = pipeline::keep_set(keep);
  const MeshInput in = make_input(positions, face_sizes, face_indices, creases, corners, holes, options);
  const FairResult r = without_gil([&] {
    const SubdivLevel level = SubdivLevel::from_input(in);
    const std::vector<Point3> start(in.positions.begin(), in.positions.end());
    fo.keep = kept_vertices(level, ks);
    std::vector<Point3> targets;
    limit_rows(level).rows.apply(start, targets);
    return fair(level, start, targets, fo);
  });
  py::dict d;
  set_items(d, "vertices", points_array(r.positions), "energy_before", r.energy_before,
               "energy_after", r.energy_after, "limit_moved_max", r.residual.max,
               "limit_moved_mean", r.residual.mean, "cage_moved_max", r.displacement.max, "kept", r.kept,
               "free", r.free);
  return d;
}

/// A target file (io/target_reader.h) as (points (n, 3), triangles (m, 3); none for a cloud).
py::tuple read_target_file(const std::string& path) {
  const TargetShape t = read_target(path);
  py::array_t<int> triangles({static_cast<py::ssize_t>(t.triangles.size()), py::ssize_t{3}});
  int* out = triangles.mutable_data();
  for (const std::array<int, 3>& tri : t.triangles)
    for (const int v : tri) *out++ = v;
  return py::make_tuple(points_array(t.points), triangles);
}

/// Fits a cage to a target (as `subd2nurbs fit`): the target's points (n, 3) and polygons (as
/// face_sizes / face_indices; none for a point cloud), fan-triangulated. Returns {vertices,
/// report}: the fitted positions and the fit report's JSON text (subd2nurbs-fit v1).
py::dict fit_cage(const DoubleArray& positions, const IntArray& face_sizes, const IntArray& face_indices,
                  const std::vector<std::tuple<int, int, double>>& creases,
                  const std::vector<std::pair<int, double>>& corners, const std::vector<int>& holes,
                  const py::dict& options, const DoubleArray& target_points, const IntArray& target_sizes,
                  const IntArray& target_indices, const std::string& target_name, std::optional<double> smoothing,
                  int levels, std::optional<int> max_iterations, std::optional<double> tolerance, double min_gain,
                  bool exact_target, const py::object& progress) {
  // As `fit --exact-target`: the recovery setting, the options given still override it.
  ShapeFitOptions fo = exact_target ? exact_target_options() : ShapeFitOptions{};
  if (smoothing) fo.smoothing = *smoothing;
  fo.levels = levels;
  if (max_iterations) fo.max_iterations = *max_iterations;
  if (tolerance) fo.tolerance = *tolerance;
  fo.min_gain = min_gain;
  pipeline::validate_shape_fit(fo);
  if (target_points.ndim() != 2 || target_points.shape(1) != 3)
    throw pipeline::SettingsError("target", "must be an array of shape (n, 3)");
  const MeshInput in = make_input(positions, face_sizes, face_indices, creases, corners, holes, options);
  const SubdivLevel level = SubdivLevel::from_input(in);
  TargetShape shape;
  const double* p = target_points.data();
  for (py::ssize_t i = 0; i < target_points.shape(0); ++i) shape.points.push_back({p[3 * i], p[3 * i + 1], p[3 * i + 2]});
  const std::vector<int> sizes(target_sizes.data(), target_sizes.data() + target_sizes.size());
  const std::vector<int> indices(target_indices.data(), target_indices.data() + target_indices.size());
  for (const int n : sizes)
    if (n < 3) throw pipeline::SettingsError("triangles", "must have at least 3 vertices per face");
  if (std::accumulate(sizes.begin(), sizes.end(), std::size_t{0}) != indices.size())
    throw pipeline::SettingsError("triangles", "face sizes do not match the indices");
  shape.triangles = fan_triangles(sizes, indices);
  const ShapeTarget target = pipeline::make_target(std::move(shape), target_name);
  const std::vector<Point3> start(in.positions.begin(), in.positions.end());
  // The fit runs without the GIL; progress(iteration, max_iterations, objective) takes it back
  // for each call and cancels the fit when it returns False (stop "cancelled": the last solved cage).
  ShapeFitProgress report;
  if (!progress.is_none())
    report = [&](int iteration, double objective) {
      py::gil_scoped_acquire locked;
      const py::object go = progress(iteration, fo.max_iterations, objective);
      return go.is_none() || go.cast<bool>();
    };
  const pipeline::ShapeFitRun run = without_gil([&] { return pipeline::run_shape_fit(level, start, target, fo, report); });
  py::dict d;
  set_items(d, "vertices", points_array(run.fit.positions), "report",
            pipeline::shape_fit_report_json(run, fo, "cage", target_name, ""));
  return d;
}

/// OCCT's own measurement of BREP text: counts, validity, area, volume.
py::dict brep_summary(const std::string& text) {
  const occt::ShapeSummary s = without_gil([&] { return occt::summarize(occt::read_brep_text(text)); });
  py::dict d;
  set_items(d, "solids", s.solids, "shells", s.shells, "faces", s.faces, "edges", s.edges,
               "free_edges", s.free_edges, "valid", s.valid, "check_message", s.check_message, "area", s.area,
               "volume", s.volume, "max_gap", s.max_gap, "max_normal_angle_deg", s.max_normal_angle_deg);
  return d;
}

/// OCCT's measurement of a STEP / IGES / BREP file.
py::dict file_summary(const std::string& path) {
  return brep_summary(without_gil([&] { return occt::brep_text(occt::read_shape(path)); }));
}

}  // namespace

PYBIND11_MODULE(_subd2nurbs, m) {
  m.doc() = "Compiled part of subd2nurbs; use the subd2nurbs package, which validates arguments.";
  py::register_exception_translator(&translate);
  m.attr("__version__") = SUBD2NURBS_VERSION;
  m.attr("OCC_VERSION") = OCC_VERSION_COMPLETE;
  m.def("input_route", [](const DoubleArray& positions, const IntArray& face_sizes, const IntArray& face_indices,
                          const std::vector<std::tuple<int, int, double>>& creases,
                          const std::vector<std::pair<int, double>>& corners, const std::vector<int>& holes,
                          const py::dict& options, const std::string& name, const std::string& input) {
    LoadedCage probe;
    probe.input = make_input(positions, face_sizes, face_indices, creases, corners, holes, options);
    const pipeline::InputRoute r = pipeline::route_input(probe, name, pipeline::input_kind(input));
    py::dict d;
    set_items(d, "kind", r.mesh ? "mesh" : "cage", "reason", r.reason);
    return d;
  });
  m.def("read_cage", &read_cage_file, py::arg("path"), py::arg("input") = "auto",
        py::arg("variants") = std::vector<std::string>{});
  m.def("check_options", [](const py::dict& options) { subdiv_options(options); });
  m.def("setting_names", &pipeline::setting_names);
  m.def("recover_quads", &recover_quads_from);
  m.def("validate", &validate);
  m.def("info", &info);
  m.def("refine", &refine);
  m.def("settings_table", &settings_table);
  m.def("error_classes", [] {  // (name, exit code, Python class) per kind of error
    py::list rows;
    for (const pipeline::ErrorClass& c : pipeline::error_classes())
      rows.append(py::make_tuple(c.name, static_cast<int>(c.exit_code), c.python));
    return rows;
  });
  py::class_<Settings> settings_class(m, "Settings",
                                      "The settings of a conversion (subd2nurbs.convert's keyword arguments), checked "
                                      "by the converter's rules when made");
  settings_class.def(py::init(&make_settings));
  for (const pipeline::SettingRow& row : pipeline::settings_table()) {  // one read-only attribute per setting
    if (!row.python) continue;
    const pipeline::SettingRow* r = &row;
    settings_class.def_property_readonly(row.name.c_str(),
                                         [r](const Settings& s) { return python_value(r->get(s.settings)); });
  }
  py::class_<Conversion, std::shared_ptr<Conversion>>(m, "Conversion",
                                                      "A conversion's result; subd2nurbs.ConversionResult wraps it")
      .def_property_readonly("report_json", [](const Conversion& c) { return pipeline::report_json(c.result); })
      .def_property_readonly("brep", &Conversion::brep)
      .def_property_readonly("brep_text", &Conversion::text)
      .def_property_readonly("warnings", [](const Conversion& c) { return pipeline::warning_texts(c.result); })
      .def_property_readonly("diagnostics", &Conversion::diagnostics)
      .def_property_readonly("curve_measures", &Conversion::curve_measures)
      .def_property_readonly("cage_vertices", [](const Conversion& c) { return points_array(c.result.cage); })
      .def_property_readonly("made_cage", &Conversion::made_cage)
      .def_property_readonly("model_size", [](const Conversion& c) { return c.result.build.set.model_size; })
      .def_property_readonly("closed", [](const Conversion& c) { return c.result.build.set.closed; })
      .def_property_readonly("preview", &Conversion::preview)
      .def("patches", &Conversion::patches)
      .def("make_preview", &Conversion::make_preview, py::arg("color"), py::arg("samples"))
      .def("write", &Conversion::write, py::arg("path"), py::arg("schema"));
  m.def("convert", &convert, py::arg("positions"), py::arg("face_sizes"), py::arg("face_indices"), py::arg("creases"),
        py::arg("corners"), py::arg("holes"), py::arg("options"), py::arg("settings"), py::arg("name"),
        py::arg("warnings"), py::arg("progress"));
  m.def("fair", &fair_cage);
  m.def("read_target", &read_target_file, py::arg("path"));
  m.def("fit", &fit_cage);
  m.def("brep_summary", &brep_summary, py::arg("text"));
  m.def("file_summary", &file_summary, py::arg("path"));
}
