#include "converter/occt/writers.h"

#include <APIHeaderSection_MakeHeader.hxx>
#include <BRepTools.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Writer.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <STEPControl_Controller.hxx>
#include <STEPControl_Writer.hxx>


#include <BRep_Builder.hxx>
#include <TCollection_HAsciiString.hxx>

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <sstream>
#include <stdexcept>

#include "converter/occt/export_error.h"
#include "converter/occt/occt_util.h"
#include "io/input_error.h"

namespace subd2nurbs::occt {

using detail::guarded;

const char* to_string(Format format) {
  switch (format) {
    case Format::Step: return "STEP";
    case Format::Iges: return "IGES";
    case Format::Brep: return "BREP";
  }
  return "?";
}

const char* to_string(StepSchema schema) {
  switch (schema) {
    case StepSchema::AP214: return "AP214";
    case StepSchema::AP242: return "AP242";
  }
  return "?";
}

Format format_from_path(const std::string& path) {
  const std::string::size_type slash = path.rfind('/');
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::string::size_type dot = name.rfind('.');
  std::string ext = dot == std::string::npos ? "" : name.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == "step" || ext == "stp") return Format::Step;
  if (ext == "iges" || ext == "igs") return Format::Iges;
  if (ext == "brep") return Format::Brep;
  throw std::invalid_argument("'" + path +
                              "': unknown output format (use .step, .stp, .iges, .igs or .brep)");
}

namespace {

/// The STEP header's time stamp from SOURCE_DATE_EPOCH (seconds since 1970, UTC; the
/// reproducible-builds convention), so that the same input gives a byte-identical file; empty
/// (OCCT's clock time) when the variable is unset or not a number.
/// `format` is strftime's: "%Y-%m-%dT%H:%M:%S" for STEP, "%Y%m%d.%H%M%S" for IGES.
std::string source_date_stamp(const char* format = "%Y-%m-%dT%H:%M:%S") {
  const char* text = std::getenv("SOURCE_DATE_EPOCH");
  if (text == nullptr || *text == '\0') return {};
  char* end = nullptr;
  errno = 0;
  const long long seconds = std::strtoll(text, &end, 10);
  if (*end != '\0' || errno != 0 || seconds < 0) return {};
  const std::time_t t = static_cast<std::time_t>(seconds);
  std::tm utc{};
  if (gmtime_r(&t, &utc) == nullptr) return {};
  char stamp[32];
  if (std::strftime(stamp, sizeof stamp, format, &utc) == 0) return {};
  return stamp;
}

void write_step(const TopoDS_Shape& shape, const std::string& file, const std::string& path,
                StepSchema schema) {
  detail::StaticSettings settings;
  guarded("step-write", -1, [&] {
    // Registers the write.step.* settings; they do not exist before the first Init().
    STEPControl_Controller::Init();
  });
  // Flat output: with "Auto" (OCCT's default) a shell or compound may be written as an
  // assembly of products, which FreeCAD 0.20 crashes on.
  settings.set("step-write", "write.step.assembly", "Off");
  // The schema must be set before the writer exists: the writer's model (and the header's
  // FILE_SCHEMA) is created with the schema current at that moment.
  settings.set("step-write", "write.step.schema",
               schema == StepSchema::AP242 ? "AP242DIS" : "AP214IS");
  guarded("step-write", -1, [&] {
    STEPControl_Writer writer;
    if (writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone)
      throw ExportError("step-transfer", -1, "the STEP translator refused the shape");
    const std::string stamp = source_date_stamp();
    if (!stamp.empty()) {
      APIHeaderSection_MakeHeader header(writer.Model());
      header.SetTimeStamp(new TCollection_HAsciiString(stamp.c_str()));
    }
    if (writer.Write(file.c_str()) != IFSelect_RetDone)
      throw WriteError(path, "the STEP writer could not write the file");
  });
}

void write_iges(const TopoDS_Shape& shape, const std::string& file, const std::string& path) {
  guarded("iges-write", -1, [&] {
    // Mode 1 = B-rep (MSBO solids, shells, faces with shared edges); mode 0 would write every
    // face as an independent trimmed surface. The unit goes into the global section.
    IGESControl_Writer writer("MM", 1);
    if (!writer.AddShape(shape))
      throw ExportError("iges-transfer", -1, "the IGES translator refused the shape");
    writer.ComputeModel();
    // With SOURCE_DATE_EPOCH the global section's two dates (of the file, of the model's last
    // change; IGES 5.3 "YYYYMMDD.HHNNSS") come from it instead of the clock, and the author field
    // (OCCT puts the login name there) is left empty: the same input gives a byte-identical file
    // whoever converts it, whenever.
    const std::string stamp = source_date_stamp("%Y%m%d.%H%M%S");
    if (!stamp.empty()) {
      IGESData_GlobalSection header = writer.Model()->GlobalSection();
      header.SetDate(new TCollection_HAsciiString(stamp.c_str()));
      header.SetLastChangeDate(new TCollection_HAsciiString(stamp.c_str()));
      header.SetAuthorName(new TCollection_HAsciiString(""));
      writer.Model()->SetGlobalSection(header);
    }
    if (!writer.Write(file.c_str()))
      throw WriteError(path, "the IGES writer could not write the file");
  });
}

void write_brep(const TopoDS_Shape& shape, const std::string& file, const std::string& path) {
  guarded("brep-write", -1, [&] {
    if (!BRepTools::Write(shape, file.c_str()))
      throw WriteError(path, "the BREP writer could not write the file");
  });
}

}  // namespace

StagedFile stage_shape(const TopoDS_Shape& shape, const std::string& path, Format format,
                       StepSchema schema) {
  if (path.empty()) throw WriteError("(empty path)", "no output file name given");
  if (shape.IsNull()) throw ExportError("write", -1, "nothing to write: the shape is null");
  StagedFile temporary(path);
  {
    std::lock_guard<std::mutex> lock(detail::exchange_mutex());
    detail::QuietMessages quiet;
    switch (format) {
      case Format::Step: write_step(shape, temporary.name(), path, schema); break;
      case Format::Iges: write_iges(shape, temporary.name(), path); break;
      case Format::Brep: write_brep(shape, temporary.name(), path); break;
    }
  }
  struct stat written;
  if (::stat(temporary.name().c_str(), &written) != 0 || written.st_size == 0)
    throw WriteError(path, "the writer produced an empty file");
  return temporary;
}

void write_shape(const TopoDS_Shape& shape, const std::string& path, Format format,
                 StepSchema schema) {
  stage_shape(shape, path, format, schema).commit();
}

std::string brep_text(const TopoDS_Shape& shape) {
  if (shape.IsNull()) throw ExportError("brep-text", -1, "nothing to write: the shape is null");
  return guarded("brep-text", -1, [&] {
    std::ostringstream out;
    BRepTools::Write(shape, out);
    if (!out) throw ExportError("brep-text", -1, "the BREP writer failed");
    return out.str();
  });
}

TopoDS_Shape read_brep_text(const std::string& text) {
  return guarded("brep-read", -1, [&] {
    std::istringstream in(text);
    TopoDS_Shape shape;
    BRep_Builder builder;
    BRepTools::Read(shape, in, builder);
    if (shape.IsNull()) throw ExportError("brep-read", -1, "the text holds no BREP shape");
    return shape;
  });
}

}  // namespace subd2nurbs::occt
