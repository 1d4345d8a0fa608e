// Writing an OCCT shape as STEP, IGES or BREP, atomically (a temporary file next to the
// target, renamed over it when complete).
#pragma once

#include <TopoDS_Shape.hxx>

#include <string>

#include "io/atomic_file.h"

namespace subd2nurbs::occt {

enum class Format { Step, Iges, Brep };

/// STEP application protocol. AP214 (OCCT's "AP214IS", FILE_SCHEMA AUTOMOTIVE_DESIGN) is what
/// most importers expect; AP242 (OCCT's "AP242DIS") is the newer one.
enum class StepSchema { AP214, AP242 };

/// The format a file name asks for: .step/.stp, .iges/.igs, .brep (case-insensitive).
/// \throw std::invalid_argument for any other (or no) extension.
Format format_from_path(const std::string& path);

/// Writes `shape` to `path`. STEP is written flat (write.step.assembly Off: FreeCAD 0.20
/// crashes on OCCT's assembly form), IGES in B-rep mode (faces, not trimmed surfaces) with
/// millimetre units, BREP in OCCT's native text format.
///
/// OCCT's settings (Interface_Static) changed for the write are restored afterwards, also on
/// failure. Writes are serialized by a process-wide lock, because those settings are global.
///
/// \throw WriteError (io/input_error.h) naming `path` if the file cannot be created, written or
///        renamed: `path` is then left as it was and no temporary file remains.
/// \throw ExportError when OCCT refuses the shape (transfer failure, OCCT exception).
void write_shape(const TopoDS_Shape& shape, const std::string& path, Format format,
                 StepSchema schema = StepSchema::AP214);

/// The same, into a StagedFile (io/atomic_file.h) that the caller commits: for several
/// outputs written together, all only after everything succeeded.
/// \throw WriteError, ExportError as write_shape
StagedFile stage_shape(const TopoDS_Shape& shape, const std::string& path, Format format,
                       StepSchema schema = StepSchema::AP214);

/// The shape in OCCT's native BREP text format (what BRepTools::Write puts in a .brep file and
/// FreeCAD's Part.Shape().importBrepFromString reads).
/// \throw ExportError when the shape is null or OCCT fails
std::string brep_text(const TopoDS_Shape& shape);

/// Reads BREP text (as written by brep_text) back into a shape.
/// \throw ExportError when OCCT cannot read it or it holds no shape
TopoDS_Shape read_brep_text(const std::string& text);

/// Human-readable names ("STEP", "IGES", "BREP"; "AP214", "AP242").
const char* to_string(Format format);
const char* to_string(StepSchema schema);

}  // namespace subd2nurbs::occt
