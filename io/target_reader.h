// Reading the target of a shape fit (core/fit/shape_target.h, `subd2nurbs fit --to`, `check
// --to`, Python fit()): a triangle mesh or a point cloud, by the file's extension
// (case-insensitive):
//   .xyz                 a point cloud: one point per line, "x y z" (further values on the line
//                        ignored); blank lines and lines starting with '#' skipped
//   .stl .ply .off .obj  (anything else: OBJ) a mesh, read as io/cage_reader.h reads a cage but
//   .gltf .glb           with quad recovery off; polygons are fan-triangulated (holes and tags
//                        ignored). A file with vertices and no faces (a PLY or OFF with vertices
//                        only, an OBJ with only `v` lines) is a point cloud.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/mesh/mesh_input.h"
#include "core/util/point3.h"

namespace subd2nurbs {

struct TargetShape {
  std::vector<Point3> points;
  std::vector<std::array<int, 3>> triangles;  ///< empty: a point cloud
};

/// The points of an .xyz text. \throw InputError naming FILE:LINE (a malformed or non-finite
/// coordinate, fewer than three values) or FILE (no points)
std::vector<Point3> parse_xyz(const std::string& text, const std::string& name);

/// Reads a target by extension (see the file comment). \throw InputError naming the file
TargetShape read_target(const std::string& path);

/// Polygons as a fan of triangles each: (v0, vi, vi+1). \throw std::invalid_argument (sizes)
std::vector<std::array<int, 3>> fan_triangles(const std::vector<int>& face_sizes, const std::vector<int>& face_indices);

}  // namespace subd2nurbs
