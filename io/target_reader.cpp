#include "io/target_reader.h"

#include <cmath>
#include <stdexcept>
#include <string_view>

#include "io/cage_reader.h"
#include "io/input_error.h"
#include "io/input_file.h"

namespace subd2nurbs {

std::vector<Point3> parse_xyz(const std::string& text, const std::string& name) {
  std::vector<Point3> points;
  int line = 0;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    ++line;
    std::string_view s(text.data() + start, end - start);
    start = end + 1;
    Point3 p{};
    int n = 0;
    size_t i = 0;
    auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == ',' || c == ';'; };
    while (n < 3) {
      while (i < s.size() && blank(s[i])) ++i;
      if (i == s.size() || (n == 0 && s[i] == '#')) break;
      size_t j = i;
      while (j < s.size() && !blank(s[j])) ++j;
      const std::string_view token = s.substr(i, j - i);
      if (!parse_double(token, p[n]))
        throw InputError(name, line, "not a number: \"" + printable(token) + "\" (expected x y z)");
      if (!std::isfinite(p[n])) throw InputError(name, line, "coordinate \"" + printable(token) + "\" is not finite");
      ++n;
      i = j;
    }
    if (n == 0) continue;  // blank line or comment
    if (n < 3) throw InputError(name, line, "expected three coordinates x y z, found " + std::to_string(n));
    points.push_back(p);
  }
  if (points.empty()) throw InputError(name, 0, "no points (expected lines \"x y z\")");
  return points;
}

std::vector<std::array<int, 3>> fan_triangles(const std::vector<int>& face_sizes, const std::vector<int>& face_indices) {
  std::vector<std::array<int, 3>> triangles;
  size_t first = 0;
  for (const int n : face_sizes) {
    if (n < 3 || first + static_cast<size_t>(n) > face_indices.size())
      throw std::invalid_argument("fan_triangles: face sizes do not match the indices");
    for (int k = 1; k + 1 < n; ++k)
      triangles.push_back({face_indices[first], face_indices[first + k], face_indices[first + k + 1]});
    first += static_cast<size_t>(n);
  }
  if (first != face_indices.size()) throw std::invalid_argument("fan_triangles: face sizes do not match the indices");
  return triangles;
}

TargetShape read_target(const std::string& path) {
  TargetShape t;
  if (lowercase_extension(path) == ".xyz") {
    t.points = parse_xyz(read_input_file(path, "an XYZ point file"), path);
    return t;
  }
  MeshReadOptions options;
  options.recover_quads = false;
  const LoadedCage cage = read_cage(path, options);
  const MeshInput& in = cage.input;
  if (in.positions.empty()) throw InputError(path, 0, "the target has no vertices");
  if (in.face_sizes.empty()) {  // a point cloud
    t.points.assign(in.positions.begin(), in.positions.end());
    return t;
  }
  // A mesh: its used vertices only (an unused vertex is no part of the shape).
  std::vector<int> index(in.positions.size(), -1);
  for (const int v : in.face_indices) {
    if (v < 0 || static_cast<size_t>(v) >= index.size()) throw InputError(path, 0, "vertex index out of range");
    if (index[v] < 0) {
      index[v] = static_cast<int>(t.points.size());
      t.points.push_back(in.positions[v]);
    }
  }
  t.triangles = fan_triangles(in.face_sizes, in.face_indices);
  for (std::array<int, 3>& tri : t.triangles)
    for (int& v : tri) v = index[v];
  return t;
}

}  // namespace subd2nurbs
