// Reading STL (io/mesh_reader.h), binary or ASCII, as a triangle soup that the shared repairs
// (io/mesh_reader.cpp) weld into a mesh.
//
// Binary: an 80-byte header (ignored: a name, "solid ...", or Materialise / VisCAM
// "COLOR=" / "MATERIAL=" colours), the facet count n (uint32, little endian), then n records of
// 50 bytes: the normal (ignored: orientation comes from the vertex order), three vertices
// (float32 x, y, z each) and two attribute bytes (ignored: per-facet colours). A file whose size
// is exactly 84 + 50 n is binary, whatever its header says.
//
// ASCII: `solid [name]`, facets `facet normal nx ny nz` / `outer loop` / `vertex x y z` (three,
// or more for a polygon) / `endloop` / `endfacet`, then `endsolid [name]`; several solids in one
// file are read as one mesh. Keywords are matched without regard to case; tokens are separated
// by any whitespace.
#include <cctype>
#include <cstring>

#include "io/input_file.h"
#include "io/mesh_reader_detail.h"

namespace subd2nurbs {

namespace {

using mesh_detail::quoted;
using mesh_detail::RawMesh;
using mesh_detail::TextCursor;

constexpr std::size_t kHeaderBytes = 84, kFacetBytes = 50;

std::uint32_t little_endian_u32(const unsigned char* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
}

float little_endian_float(const unsigned char* p) {
  const std::uint32_t bits = little_endian_u32(p);
  float x;
  std::memcpy(&x, &bits, sizeof x);
  return x;
}

bool keyword_is(std::string_view token, std::string_view keyword) {
  if (token.size() != keyword.size()) return false;
  for (std::size_t i = 0; i < token.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(token[i])) != keyword[i]) return false;
  return true;
}

/// Starts (after blanks and a byte-order mark) with the keyword `solid`.
bool starts_with_solid(std::string_view bytes) {
  bytes = mesh_detail::skip_utf8_bom(bytes);
  while (!bytes.empty() && std::isspace(static_cast<unsigned char>(bytes[0]))) bytes.remove_prefix(1);
  return bytes.size() >= 5 && keyword_is(bytes.substr(0, 5), "solid") &&
         (bytes.size() == 5 || std::isspace(static_cast<unsigned char>(bytes[5])));
}

RawMesh read_binary(std::string_view bytes, std::size_t facets, const std::string& name, const MeshReadOptions& options) {
  if (facets > static_cast<std::size_t>(options.max_elements))
    throw InputError(name, 0, "binary STL with " + std::to_string(facets) + " facets; at most " +
                                  std::to_string(options.max_elements) + " are read");
  RawMesh raw;
  raw.locator = LoadedCage::Locator::Element;
  raw.face_unit = raw.vertex_unit = "facet";
  raw.positions.reserve(3 * facets);
  raw.vertex_loc.reserve(3 * facets);
  raw.face_sizes.assign(facets, 3);
  raw.face_indices.reserve(3 * facets);
  raw.face_loc.reserve(facets);
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  for (std::size_t i = 0; i < facets; ++i) {
    const unsigned char* record = data + kHeaderBytes + kFacetBytes * i;
    const int number = static_cast<int>(i) + 1;
    for (int corner = 0; corner < 3; ++corner) {
      const unsigned char* p = record + 12 + 12 * corner;
      raw.face_indices.push_back(static_cast<std::int64_t>(raw.positions.size()));
      raw.positions.push_back({little_endian_float(p), little_endian_float(p + 4), little_endian_float(p + 8)});
      raw.vertex_loc.push_back(number);
    }
    raw.face_loc.push_back(number);
  }
  return raw;
}

RawMesh read_ascii(std::string_view text, const std::string& name) {
  RawMesh raw;
  TextCursor in(mesh_detail::skip_utf8_bom(text));
  std::string_view token;
  auto fail = [&](const std::string& message) -> InputError { return InputError(name, in.line(), message); };
  auto expect = [&](std::string_view keyword) {
    if (!in.next(token)) throw InputError(name, in.line(), "the file ends where '" + std::string(keyword) + "' was expected");
    if (!keyword_is(token, keyword)) throw fail("expected '" + std::string(keyword) + "', found " + quoted(token));
  };
  expect("solid");
  in.skip_line();  // the solid's name
  bool in_solid = true;
  while (in.next(token)) {
    if (!in_solid) {
      if (!keyword_is(token, "solid")) throw fail("expected 'solid' after 'endsolid', found " + quoted(token));
      in.skip_line();
      in_solid = true;
      continue;
    }
    if (keyword_is(token, "endsolid")) {
      in.skip_line();
      in_solid = false;
      continue;
    }
    if (!keyword_is(token, "facet")) throw fail("expected 'facet' or 'endsolid', found " + quoted(token));
    const int facet_line = in.line();
    // The normal (ignored): "normal" and up to three values before "outer".
    if (!in.next(token)) throw fail("the file ends inside a facet");
    if (keyword_is(token, "normal")) {
      for (int k = 0; k < 4 && in.next(token) && !keyword_is(token, "outer"); ++k)
        if (k == 3) throw fail("expected 'outer loop' after the facet normal, found " + quoted(token));
    }
    if (!keyword_is(token, "outer")) throw fail("expected 'outer loop', found " + quoted(token));
    expect("loop");
    int corners = 0;
    for (;;) {
      if (!in.next(token)) throw fail("the file ends inside a facet");
      if (keyword_is(token, "endloop")) break;
      if (!keyword_is(token, "vertex")) throw fail("expected 'vertex' or 'endloop', found " + quoted(token));
      std::array<double, 3> p{};
      const int vertex_line = in.line();
      for (double& x : p) {
        if (!in.next(token)) throw fail("the file ends inside a vertex");
        if (!parse_double(token, x)) throw fail("vertex coordinate " + quoted(token) + " is not a number");
      }
      raw.face_indices.push_back(static_cast<std::int64_t>(raw.positions.size()));
      raw.positions.push_back(p);
      raw.vertex_loc.push_back(vertex_line);
      ++corners;
    }
    expect("endfacet");
    raw.face_sizes.push_back(corners);
    raw.face_loc.push_back(facet_line);
  }
  return raw;
}

}  // namespace

LoadedCage parse_stl(const std::string& bytes, const std::string& name, const MeshReadOptions& options) {
  // Binary when the size matches the facet count exactly.
  std::size_t facets = 0, expected = 0;
  if (bytes.size() >= kHeaderBytes) {
    facets = little_endian_u32(reinterpret_cast<const unsigned char*>(bytes.data()) + 80);
    expected = kHeaderBytes + kFacetBytes * facets;
    if (bytes.size() == expected)
      return mesh_detail::finish_mesh(read_binary(bytes, facets, name, options), name, options);
  }
  if (starts_with_solid(bytes)) {
    try {
      return mesh_detail::finish_mesh(read_ascii(bytes, name), name, options);
    } catch (const InputError& e) {
      // A binary file whose header starts with "solid" but whose size is wrong: say both.
      if (bytes.size() < kHeaderBytes || std::memchr(bytes.data(), '\0', bytes.size()) == nullptr || e.code()) throw;
      throw InputError(name, 0, "neither binary STL (bytes 80-83 announce " + std::to_string(facets) +
                                    " facets, which take " + std::to_string(expected) + " bytes; the file has " +
                                    std::to_string(bytes.size()) + ") nor ASCII STL (line " +
                                    std::to_string(e.line()) + ": " + e.message() + ")");
    }
  }
  if (bytes.size() < kHeaderBytes)
    throw InputError(name, 0, "not an STL file: " + std::to_string(bytes.size()) +
                                  " bytes, too short for binary STL (84 bytes of header and count), and it does not "
                                  "start with 'solid' (ASCII STL)");
  if (bytes.size() < expected)
    throw InputError(name, 0, "binary STL truncated: bytes 80-83 announce " + std::to_string(facets) + " facets, which take " +
                                  std::to_string(expected) + " bytes; the file has " + std::to_string(bytes.size()));
  // Longer than its facets: read them, and say that the rest was ignored.
  RawMesh raw = read_binary(bytes, facets, name, options);
  raw.diagnostics.push_back({"trailing-bytes", ElementKind::None, 0,
                             std::to_string(bytes.size() - expected) + " bytes after the last of the " +
                                 std::to_string(facets) + " facets were ignored"});
  return mesh_detail::finish_mesh(std::move(raw), name, options);
}

LoadedCage read_stl(const std::string& path, const MeshReadOptions& options) {
  return parse_stl(read_input_file(path, "an STL file"), path, options);
}

}  // namespace subd2nurbs
