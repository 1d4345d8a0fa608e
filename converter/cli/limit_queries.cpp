#include "converter/cli/limit_queries.h"

#include <sstream>
#include <stdexcept>

#include "io/input_error.h"
#include "io/input_file.h"

namespace subd2nurbs::cli {

namespace {

bool parse_int(const std::string& s, int& x) {
  try {
    size_t used = 0;
    const long long v = std::stoll(s, &used);
    if (used != s.size() || v < 0 || v > 2147483647LL) return false;
    x = static_cast<int>(v);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

std::vector<Query> read_queries(std::istream& in, const std::string& name, const PolyMesh& mesh) {
  std::vector<Query> queries;
  std::string text;
  int line_no = 0;
  while (std::getline(in, text)) {
    ++line_no;
    std::istringstream tokens(text);
    std::vector<std::string> t;
    for (std::string w; tokens >> w;) t.push_back(w);
    if (t.empty() || t[0][0] == '#') continue;
    auto fail = [&](const std::string& why) { throw InputError(name, line_no, why); };
    if (t.size() != 3 && t.size() != 4)
      fail("expected \"f u v\" or \"f s u v\", got " + std::to_string(t.size()) + " fields");
    Query q;
    q.line = line_no;
    if (!parse_int(t[0], q.face)) fail("face index '" + printable(t[0], 40) + "' is not a non-negative integer");
    if (t.size() == 4 && !parse_int(t[1], q.sub))
      fail("sub-face index '" + printable(t[1], 40) + "' is not a non-negative integer");
    const std::string& us = t[t.size() - 2];
    const std::string& vs = t[t.size() - 1];
    if (!parse_double(us, q.u) || !parse_double(vs, q.v))
      fail("parameters '" + printable(us, 40) + " " + printable(vs, 40) + "' are not numbers");
    if (!(q.u >= 0 && q.u <= 1 && q.v >= 0 && q.v <= 1))
      fail("parameters (" + printable(us, 40) + ", " + printable(vs, 40) + ") are outside [0,1]^2");
    if (q.face >= mesh.num_faces())
      fail("no face " + t[0] + " (the mesh has " + std::to_string(mesh.num_faces()) + " faces)");
    const int size = mesh.face_size(q.face);
    if (size != 4 && t.size() == 3)
      fail("face " + t[0] + " has " + std::to_string(size) +
           " sides: give its sub-face, \"f s u v\" with s in 0.." + std::to_string(size - 1));
    if (t.size() == 4 && q.sub >= (size == 4 ? 1 : size))
      fail("face " + t[0] + " has no sub-face " + t[1] +
           (size == 4 ? " (a quad has only sub-face 0)"
                      : " (sub-faces 0.." + std::to_string(size - 1) + ")"));
    queries.push_back(q);
  }
  if (in.bad()) throw InputError(name, 0, "read error");
  return queries;
}


}  // namespace subd2nurbs::cli
