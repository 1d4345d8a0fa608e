#include "io/patch_json.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "io/atomic_file.h"

namespace subd2nurbs {

namespace {

class JsonWriter {
 public:
  std::string& out() { return s_; }

  void number(double x, const char* what) {
    if (!std::isfinite(x))
      throw std::invalid_argument(std::string("patch JSON: non-finite value in ") + what);
    if (x == 0 && std::signbit(x)) {  // "%.17g" gives "-0", which many readers take as integer 0
      s_ += "-0.0";
      return;
    }
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    for (char* c = buf; *c; ++c)
      if (*c == ',') *c = '.';  // a decimal comma from a non-C LC_NUMERIC locale
    s_ += buf;
  }
  void integer(long long i) { s_ += std::to_string(i); }
  void boolean(bool b) { s_ += b ? "true" : "false"; }
  /// Only for fixed ASCII names without quotes or backslashes.
  void string(const char* str) {
    s_ += '"';
    s_ += str;
    s_ += '"';
  }
  /// `"name":` preceded by a comma unless it is the first key of its object.
  void key(const char* name, bool first = false) {
    if (!first) s_ += ',';
    string(name);
    s_ += ':';
  }
  template <class T, class Fn>
  void array(const T& items, Fn&& fn) {
    s_ += '[';
    bool first = true;
    for (const auto& item : items) {
      if (!first) s_ += ',';
      first = false;
      fn(item);
    }
    s_ += ']';
  }
  void point(const Point3& p, const char* what) {
    array(p, [&](double x) { number(x, what); });
  }
  void points(const std::vector<Point3>& ps, const char* what) {
    array(ps, [&](const Point3& p) { point(p, what); });
  }
  void knots(const KnotVector& k, const char* what) {
    s_ += '{';
    key("values", true);
    array(k.knots, [&](double x) { number(x, what); });
    key("mults");
    array(k.mults, [&](int m) { integer(m); });
    key("periodic");
    boolean(k.periodic);
    s_ += '}';
  }

 private:
  std::string s_;
};

/// The part [t0, t1] of a patch side that a curve covers (pieces of split sides).
void write_range(JsonWriter& w, double t0, double t1) {
  w.key("t0");
  w.number(t0, "side piece t0");
  w.key("t1");
  w.number(t1, "side piece t1");
}

void write_patch(JsonWriter& w, const NurbsPatch& p) {
  std::string& s = w.out();
  s += '{';
  w.key("kind", true);
  w.string(to_string(p.kind));
  w.key("degree");
  s += '[' + std::to_string(p.degree_u) + ',' + std::to_string(p.degree_v) + ']';
  w.key("knots_u");
  w.knots(p.knots_u, "knots_u");
  w.key("knots_v");
  w.knots(p.knots_v, "knots_v");
  w.key("num_poles");
  s += '[' + std::to_string(p.num_poles_u) + ',' + std::to_string(p.num_poles_v) + ']';
  w.key("poles");
  w.points(p.poles, "patch poles");
  if (!p.weights.empty()) {
    w.key("weights");
    w.array(p.weights, [&](double x) { w.number(x, "patch weights"); });
  }
  w.key("base_faces");
  w.array(p.base_faces, [&](int f) { w.integer(f); });
  if (!p.cells.empty()) {  // a packed face: its coarse quads, one cell [u, u+1] x [v, v+1] each
    w.key("cells");
    w.array(p.cells, [&](const PatchCell& c) {
      s += '{';
      w.key("base_face", true);
      w.integer(c.base_face);
      w.key("coarse_face");
      w.integer(c.coarse_face);
      w.key("u");
      w.integer(c.u);
      w.key("v");
      w.integer(c.v);
      w.key("rotation");
      w.integer(c.rotation);
      s += '}';
    });
  }
  w.key("corners");
  w.array(p.corners, [&](int c) { w.integer(c); });
  w.key("curves");
  w.array(p.curves, [&](int c) { w.integer(c); });
  w.key("curve_reversed");
  w.array(p.curve_reversed, [&](bool b) { w.boolean(b); });
  bool split = false;
  for (const auto& pieces : p.split_sides) split = split || !pieces.empty();
  if (split) {  // sides made of several curves (a packed face, a polar cap), counter-clockwise
    w.key("split_sides");
    w.array(p.split_sides, [&](const std::vector<SidePiece>& pieces) {
      w.array(pieces, [&](const SidePiece& q) {
        s += '{';
        w.key("curve", true);
        w.integer(q.curve);
        w.key("reversed");
        w.boolean(q.reversed);
        write_range(w, q.t0, q.t1);
        s += '}';
      });
    });
  }
  s += '}';
}

void write_curve(JsonWriter& w, const BoundaryCurve& c) {
  std::string& s = w.out();
  s += '{';
  w.key("corners", true);
  s += '[' + std::to_string(c.corner0) + ',' + std::to_string(c.corner1) + ']';
  w.key("degree");
  w.integer(c.degree);
  w.key("knots");
  w.knots(c.knots, "curve knots");
  w.key("poles");
  w.points(c.poles, "curve poles");
  w.key("continuity");
  w.string(to_string(c.continuity));
  w.key("uses");
  w.array(c.uses, [&](const CurveUse& u) {
    s += '{';
    w.key("patch", true);
    w.integer(u.patch);
    w.key("side");
    w.integer(u.side);
    w.key("reversed");
    w.boolean(u.reversed);
    if (u.t0 != 0 || u.t1 != 1) write_range(w, u.t0, u.t1);  // a piece of a split side (polar cap)
    s += '}';
  });
  s += '}';
}

void write_corner(JsonWriter& w, const PatchCorner& c) {
  std::string& s = w.out();
  s += '{';
  w.key("position", true);
  w.point(c.position, "corner position");
  w.key("base_vertex");
  w.integer(c.base_vertex);
  s += '}';
}

/// `"name":[` + one item per line + `]` (`"name":[]` if there are none).
template <class T, class Fn>
void write_list(JsonWriter& w, const char* name, const std::vector<T>& items, Fn&& fn) {
  std::string& s = w.out();
  w.key(name, true);
  s += '[';
  for (size_t i = 0; i < items.size(); ++i) {
    s += i == 0 ? "\n" : ",\n";
    fn(w, items[i]);
  }
  if (!items.empty()) s += '\n';
  s += ']';
}

}  // namespace

std::string patch_set_to_json(const PatchSet& ps) {
  JsonWriter w;
  std::string& s = w.out();
  s += '{';
  w.key("format", true);
  w.string("subd2nurbs-patches");
  w.key("version");
  w.integer(1);
  w.key("model_size");
  w.number(ps.model_size, "model_size");
  w.key("closed");
  w.boolean(ps.closed);
  s += ",\n";
  write_list(w, "patches", ps.patches, write_patch);
  s += ",\n";
  write_list(w, "curves", ps.curves, write_curve);
  s += ",\n";
  write_list(w, "corners", ps.corners, write_corner);
  s += "}\n";
  return std::move(s);
}

void write_patch_json(const std::string& path, const PatchSet& patches) {
  const std::string text = patch_set_to_json(patches);
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace subd2nurbs
