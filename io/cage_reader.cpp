#include "io/cage_reader.h"

#include <sys/stat.h>

#include <fstream>

#include "io/gltf_reader.h"
#include "io/input_file.h"

namespace subd2nurbs {

namespace {

/// Extensions of formats that are not read (3D interchange, CAD, images, archives): refused by
/// name rather than parsed as OBJ.
bool foreign_extension(const std::string& ext) {
  static const char* const kForeign[] = {".fbx", ".abc", ".blend", ".dae", ".3ds", ".max", ".ma", ".mb", ".c4d",
                                         ".x3d", ".wrl", ".vrml", ".3mf", ".amf", ".step", ".stp", ".iges",
                                         ".igs", ".brep", ".sldprt", ".ipt", ".f3d", ".3dm", ".skp", ".dxf",
                                         ".dwg", ".lwo", ".usdnc", ".zip", ".png", ".jpg", ".jpeg", ".pdf"};
  for (const char* f : kForeign)
    if (ext == f) return true;
  return false;
}

/// The file's first bytes (empty when it cannot be opened: the OBJ reader then names why).
std::string head(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return {};
  std::ifstream in(path, std::ios::binary);
  std::string bytes(4096, '\0');
  if (!in) return {};
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  return bytes;
}

}  // namespace

CageFormat cage_format(const std::string& path) {
  const std::string ext = lowercase_extension(path);
  if (ext == ".obj") return CageFormat::Obj;
  if (ext == ".glb" || ext == ".gltf") return CageFormat::Gltf;
  if (ext == ".stl") return CageFormat::Stl;
  if (ext == ".ply") return CageFormat::Ply;
  if (ext == ".off") return CageFormat::Off;
  if (ext == ".usd" || ext == ".usda" || ext == ".usdc" || ext == ".usdz") return CageFormat::Usd;
  return CageFormat::Other;
}

LoadedCage read_cage(const std::string& path, const MeshReadOptions& options, const UsdReadOptions& usd) {
  switch (cage_format(path)) {
    case CageFormat::Obj: return read_obj(path);
    case CageFormat::Gltf: return read_gltf(path);
    case CageFormat::Stl: return read_stl(path, options);
    case CageFormat::Ply: return read_ply(path, options);
    case CageFormat::Off: return read_off(path, options);
    case CageFormat::Usd: return read_usd(path, usd);
    case CageFormat::Other: break;
  }
  const std::string ext = lowercase_extension(path);
  if (foreign_extension(ext))
    throw InputError(path, 0, "not a format subd2nurbs reads: '" + printable(ext) +
                                  "' files are not read (OBJ, glTF/GLB, STL, PLY, OFF and USD are; export the cage to one of those)");
  // Other or no extension: by content. (A FIFO or directory is left to the OBJ reader, which
  // refuses it without blocking: head() opens only regular files.)
  const std::string start = head(path);
  if (looks_like_usd(start)) return read_usd(path, usd);
  if (start.find('\0') != std::string::npos)
    throw InputError(path, 0, "not a format subd2nurbs reads: binary content that is not a known format "
                              "(OBJ, glTF/GLB, STL, PLY, OFF and USD are read; name the file by its format's extension)");
  return read_obj(path);
}

}  // namespace subd2nurbs
