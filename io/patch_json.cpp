#include "io/patch_json.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/json_writer.h"

namespace subd2nurbs {

namespace {

void write_knots(JsonWriter& w, const KnotVector& k, const char* what) {
  w.begin_object();
  w.key("values").numbers(k.knots, what);
  w.key("mults").integers(k.mults);
  w.key("periodic").boolean(k.periodic);
  w.end_object();
}

template <class Points>
void write_points(JsonWriter& w, const Points& ps, const char* what) {
  w.begin_array();
  for (const Point3& p : ps) w.point(p, what);
  w.end_array();
}

/// The part [t0, t1] of a patch side that a curve covers (pieces of split sides).
void write_range(JsonWriter& w, double t0, double t1) {
  w.key("t0").number(t0, "side piece t0");
  w.key("t1").number(t1, "side piece t1");
}

void write_patch(JsonWriter& w, const NurbsPatch& p) {
  w.begin_object();
  w.key("kind").string(to_string(p.kind));
  w.key("degree").integers(std::vector<int>{p.degree_u, p.degree_v});
  w.key("knots_u");
  write_knots(w, p.knots_u, "knots_u");
  w.key("knots_v");
  write_knots(w, p.knots_v, "knots_v");
  w.key("num_poles").integers(std::vector<int>{p.num_poles_u, p.num_poles_v});
  w.key("poles");
  write_points(w, p.poles, "patch poles");
  if (!p.weights.empty()) w.key("weights").numbers(p.weights, "patch weights");
  w.key("base_faces").integers(p.base_faces);
  if (!p.cells.empty()) {  // a packed face: its coarse quads, one cell [u, u+1] x [v, v+1] each
    w.key("cells").begin_array();
    for (const PatchCell& c : p.cells) {
      w.begin_object();
      w.members("base_face", c.base_face, "coarse_face", c.coarse_face, "u", c.u, "v", c.v, "rotation", c.rotation);
      w.end_object();
    }
    w.end_array();
  }
  w.key("corners").integers(p.corners);
  w.key("curves").integers(p.curves);
  w.key("curve_reversed").begin_array();
  for (const bool b : p.curve_reversed) w.boolean(b);
  w.end_array();
  bool split = false;
  for (const auto& pieces : p.split_sides) split = split || !pieces.empty();
  if (split) {  // sides made of several curves (a packed face, a polar cap), counter-clockwise
    w.key("split_sides").begin_array();
    for (const std::vector<SidePiece>& pieces : p.split_sides) {
      w.begin_array();
      for (const SidePiece& q : pieces) {
        w.begin_object();
        w.members("curve", q.curve, "reversed", q.reversed);
        write_range(w, q.t0, q.t1);
        w.end_object();
      }
      w.end_array();
    }
    w.end_array();
  }
  w.end_object();
}

void write_curve(JsonWriter& w, const BoundaryCurve& c) {
  w.begin_object();
  w.key("corners").integers(std::vector<int>{c.corner0, c.corner1});
  w.key("degree").integer(c.degree);
  w.key("knots");
  write_knots(w, c.knots, "curve knots");
  w.key("poles");
  write_points(w, c.poles, "curve poles");
  w.key("continuity").string(to_string(c.continuity));
  w.key("uses").begin_array();
  for (const CurveUse& u : c.uses) {
    w.begin_object();
    w.members("patch", u.patch, "side", u.side, "reversed", u.reversed);
    if (u.t0 != 0 || u.t1 != 1) write_range(w, u.t0, u.t1);  // a piece of a split side (polar cap)
    w.end_object();
  }
  w.end_array();
  w.end_object();
}

void write_corner(JsonWriter& w, const PatchCorner& c) {
  w.begin_object();
  w.key("position").point(c.position, "corner position");
  w.key("base_vertex").integer(c.base_vertex);
  w.end_object();
}

/// On a line of its own: `"name":[` + one item per line + `]` (`"name":[]` if there are none).
template <class T, class Fn>
void write_list(JsonWriter& w, const char* name, const std::vector<T>& items, Fn&& fn) {
  w.break_line(0).key(name).begin_array(0, 0);
  for (const T& item : items) fn(w, item);
  w.end_array();
}

}  // namespace

std::string patch_set_to_json(const PatchSet& ps) {
  JsonWriter w(JsonWriter::Numbers::Exact, JsonWriter::Spacing::Compact, "patch JSON");
  w.begin_object();
  w.members("format", "subd2nurbs-patches", "version", 1);
  w.key("model_size").number(ps.model_size, "model_size");
  w.key("closed").boolean(ps.closed);
  write_list(w, "patches", ps.patches, write_patch);
  write_list(w, "curves", ps.curves, write_curve);
  write_list(w, "corners", ps.corners, write_corner);
  w.end_object();
  return w.take() + "\n";
}

void write_patch_json(const std::string& path, const PatchSet& patches) {
  const std::string text = patch_set_to_json(patches);
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace subd2nurbs
