// Frames on a quad mesh, shared by the patch builder and the deviation measurement.
//
// A frame is a corner c of a quad: origin at corner_vertex(c), x axis along c's edge (toward
// the next corner), y axis toward the previous corner. Faces are counter-clockwise, so x, y
// and the face normal are right-handed. Bezier nets are stored per face in the face's own
// frame (its first corner), 16 points, index i * 4 + j with i along x.
#pragma once

#include <stdexcept>

#include "core/mesh/poly_mesh.h"

namespace subd2nurbs::frames {

/// Position of corner c within its face (0 = the face's own frame).
inline int rotation_in_face(const PolyMesh& m, int c) { return c - m.face_begin(m.corner_face(c)); }

/// Bezier index (i, j) in the frame of the face's corner r -> index in the face's own frame.
inline int face_net_index(int r, int i, int j) {
  switch (r) {
    case 0: return i * 4 + j;
    case 1: return (3 - j) * 4 + i;
    case 2: return (3 - i) * 4 + (3 - j);
    default: return j * 4 + (3 - i);
  }
}

/// Frame of the quad one step along +x (across the edge x = 1), same orientation.
inline int step_x(const PolyMesh& m, int c) {
  const int t = m.twin(m.next(c));
  if (t < 0) throw std::logic_error("quad frames: walked off the mesh (x)");
  return m.next(t);
}

/// Frame of the quad one step along +y (across the edge y = 1), same orientation.
inline int step_y(const PolyMesh& m, int c) {
  const int t = m.twin(m.next(m.next(c)));
  if (t < 0) throw std::logic_error("quad frames: walked off the mesh (y)");
  return t;
}

}  // namespace subd2nurbs::frames
