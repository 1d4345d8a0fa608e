// Typed errors and diagnostics of the core. Every error names the element it is about,
// so front ends (CLI, Python, FreeCAD) can map it back to a file line or a selection.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "core/util/error.h"

namespace subd2nurbs {

/// What kind of mesh element an error or diagnostic refers to.
enum class ElementKind { None, Vertex, Face, Edge, Tag };

/// Stable machine-readable codes for invalid input. Tests check these, not the message text.
enum class MeshErrorCode {
  EmptyMesh,               ///< no faces or no vertices
  NonFiniteCoordinate,     ///< NaN or Inf in a vertex position
  FaceTooSmall,            ///< a face with fewer than 3 vertices
  IndexOutOfRange,         ///< a face refers to a vertex that does not exist
  RepeatedVertexInFace,    ///< the same vertex appears twice in one face
  NonManifoldEdge,         ///< an edge shared by more than two faces
  InconsistentOrientation, ///< two neighbouring faces traverse their shared edge the same way
  NonManifoldVertex,       ///< the faces around a vertex do not form one connected fan
  InvalidTag,              ///< a crease/corner/hole tag names something that does not exist
  CoordinateOutOfRange,    ///< a coordinate beyond +-kMaxCoordinate (core/mesh/validate.h)
  FaceTooLarge,            ///< a face with more than kMaxFaceSize vertices
  ValenceTooHigh,          ///< a vertex on more than kMaxValence edges
};

const char* to_string(MeshErrorCode code);

/// Thrown by validation. `element` / `index` name the offending element; `index2` is a
/// second id where useful (the other vertex of an edge, the second face of a conflict).
class InvalidMeshError : public Error {
 public:
  InvalidMeshError(MeshErrorCode code, ElementKind element, long index, long index2,
                   const std::string& message)
      : Error(ErrorKind::Input, message), code_(code), element_(element), index_(index),
        index2_(index2) {}
  MeshErrorCode code() const { return code_; }
  ElementKind element() const { return element_; }
  long index() const { return index_; }
  long index2() const { return index2_; }

 private:
  MeshErrorCode code_;
  ElementKind element_;
  long index_;
  long index2_;
};

/// A non-fatal finding (the input is usable, but something deserves the user's attention).
struct Diagnostic {
  std::string code;      ///< stable identifier, e.g. "unused-vertex"
  ElementKind element = ElementKind::None;
  long index = -1;
  std::string message;
};

using Diagnostics = std::vector<Diagnostic>;

}  // namespace subd2nurbs
