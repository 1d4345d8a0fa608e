#include "converter/pipeline/resources.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <set>
#include <utility>

#include "converter/pipeline/text.h"
#include "io/input_file.h"

namespace subd2nurbs::pipeline {

double default_max_memory() {
  double physical = 0;
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) physical = static_cast<double>(pages) * static_cast<double>(page);
  double limit = physical > 0 ? physical : 4.0 * (1 << 30);
  for (int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    struct rlimit r;
    if (::getrlimit(resource, &r) == 0 && r.rlim_cur != RLIM_INFINITY)
      limit = std::min(limit, static_cast<double>(r.rlim_cur));
  }
  return std::max(0.75 * limit, 256.0 * (1 << 20));
}

std::string bytes_text(double bytes) {
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB"};
  int u = 0;
  while (bytes >= 1024 && u < 5) {
    bytes /= 1024;
    ++u;
  }
  return short_number(bytes) + " " + units[u];
}

bool parse_memory_size(const std::string& text, double& bytes) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  if (end == begin) return false;
  std::string suffix(end);
  for (char& c : suffix) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  double scale = 1;
  if (!suffix.empty() && std::string("KMGT").find(suffix[0]) != std::string::npos) {
    scale = std::pow(1024.0, 1 + static_cast<int>(std::string("KMGT").find(suffix[0])));
    suffix.erase(0, 1);
    if (suffix == "I" || suffix == "IB" || suffix == "B") suffix.clear();
  } else if (suffix == "B") {
    suffix.clear();
  }
  if (!suffix.empty() || !(value > 0) || !std::isfinite(value * scale)) return false;
  bytes = value * scale;
  return true;
}

ResourceEstimate estimate_conversion(const SubdivLevel& base, int extra_levels, bool build_brep) {
  // The patch builder refines only locally (core/patch, docs/patches.md): its work is the
  // polynomial pieces. Every coarse quad is one piece, plus at each irregular corner 3 per level
  // down to its fan's zone and the zone's 4, plus along each semi-sharp edge two rows of pieces
  // per level until its sharpness has decayed. The B-rep and the STEP writer then cost per face.
  const PolyMesh& m = base.mesh;
  const double coarse_quads = m.all_quads() ? m.num_faces() : m.num_corners();
  const int extra = std::max(0, extra_levels);
  double irregular_corners = 0;
  for (int f = 0; f < m.num_faces(); ++f) {
    if (m.face_size(f) != 4) irregular_corners += m.face_size(f);  // each child quad's centre corner
    for (int h = m.face_begin(f); h < m.face_end(f); ++h) {
      const int v = m.corner_vertex(h);
      if (m.is_boundary_vertex(v) || m.valence(v) != 4) irregular_corners += m.face_size(f) == 4 ? 1 : 2;
    }
  }
  double semi_pieces = 0;
  for (int e = 0; e < m.num_edges(); ++e) {
    const float s = base.edge_sharpness[e];
    if (!(s > 0 && s < kInfiniteSharpness)) continue;
    const int levels = static_cast<int>(std::ceil(s)) + 1;
    semi_pieces += 2.0 * 4.0 * std::pow(2.0, levels);  // two faces, two rows per level, 2^j per row
  }
  ResourceEstimate e;
  e.faces = coarse_quads + irregular_corners * (3.0 * (2 + extra) + 4) + semi_pieces;
  e.patches = coarse_quads;
  e.poles = 16.0 * coarse_quads + irregular_corners * 2.0 * (2 + extra) * 8.0;
  e.bytes = e.faces * kConvertBytesPerPiece + coarse_quads * (build_brep ? kConvertBytesPerFace : kConvertBytesPerFaceNoBrep);
  // Irregular vertices: one eigenbasis per distinct valence (limit evaluation), each with a
  // few (2n+8)^2 matrices of doubles. n-gons give level-1 vertices of valence n.
  std::set<int> valences;
  for (int v = 0; v < m.num_vertices(); ++v)
    if (!m.is_boundary_vertex(v) && m.valence(v) != 4) valences.insert(m.valence(v));
  for (int f = 0; f < m.num_faces(); ++f)
    if (m.face_size(f) != 4) valences.insert(m.face_size(f));
  for (int n : valences) e.bytes += 4.0 * 8.0 * (2.0 * n + 8) * (2.0 * n + 8);
  return e;
}

ResourceEstimate estimate_refinement(const SubdivLevel& base, int levels) {
  const PolyMesh& m = base.mesh;
  ResourceEstimate e;
  e.faces = levels <= 0 ? m.num_faces() : m.num_corners() * std::pow(4.0, levels - 1);
  e.bytes = e.faces * kRefineBytesPerFace;
  return e;
}

void validate(const ResourceLimits& limits) {
  for (const auto& [setting, value] : {std::pair{"max_faces", limits.max_faces}, std::pair{"max_memory", limits.max_memory}})
    if (value && !(*value > 0 && std::isfinite(*value))) throw SettingsError(setting, "must be a positive number");
}

void check_refine_levels(int levels) {
  if (levels < 0 || levels > kMaxRefineLevels)
    throw SettingsError("levels", "must be 0 .. " + std::to_string(kMaxRefineLevels));
}

double memory_size(const std::string& text) {
  double bytes = 0;
  if (!parse_memory_size(text, bytes))
    throw SettingsError("max_memory", "'" + printable(text, 40) + "' is not a size (bytes, or a number with K, M, G or T, e.g. 8G)");
  return bytes;
}

void check_resources(const ResourceEstimate& estimate, const ResourceLimits& limits, double default_max_faces,
                     const std::string& what, const std::string& advice) {
  const double max_faces = limits.max_faces.value_or(default_max_faces);
  const double max_memory = limits.max_memory ? *limits.max_memory : default_max_memory();
  if (estimate.faces > max_faces)
    throw ResourceError(what + " would make about " + short_number(estimate.faces) + " faces (limit " +
                        short_number(max_faces) + (limits.max_faces ? "" : ", the default") + "); " + advice +
                        ", or raise the limit with --max-faces N (Python: max_faces=N)");
  if (estimate.bytes > max_memory)
    throw ResourceError(what + " would need about " + bytes_text(estimate.bytes) + " of memory (limit " +
                        bytes_text(max_memory) +
                        (limits.max_memory ? "" : ", 3/4 of the memory available to this process") + "); " +
                        advice + ", or raise the limit with --max-memory SIZE (Python: max_memory=bytes)");
}

}  // namespace subd2nurbs::pipeline
