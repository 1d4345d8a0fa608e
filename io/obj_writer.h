// Writing a cage or refined level as OBJ with OpenSubdiv-style tags (see obj_reader.h), so
// that reading the file back reproduces the level: same vertices (bit for bit), faces and
// effective sharpness, holes and options.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "core/refine/refiner.h"
#include "core/util/point3.h"

namespace subd2nurbs {

/// Writes `level` with vertex positions `positions` to `path`, atomically (the file is
/// either completely written or left untouched). Coordinates and sharpness use "%.17g".
/// Tags written: interpolateboundary (always), creasemethod (if Chaikin), smoothtriangles
/// (if Smooth), a crease per interior edge with sharpness > 0, a corner per vertex with
/// sharpness > 0 except those sharpened automatically (see is_automatic_corner), and the hole
/// faces. Boundary edges are sharp without a tag, except under BoundaryRule::None: there an
/// untagged boundary makes the faces around it holes, so all boundary edges are written as
/// infinitely sharp creases and the holes are given explicitly.
/// \throw std::invalid_argument if positions and level do not match
/// \throw WriteError if the file cannot be written
void write_obj(const std::string& path, const std::vector<Point3>& positions,
               const SubdivLevel& level);
/// The same onto a stream (e.g. a StagedFile's, io/atomic_file.h, committed with other outputs).
void write_obj(std::ostream& out, const std::vector<Point3>& positions, const SubdivLevel& level);

}  // namespace subd2nurbs
