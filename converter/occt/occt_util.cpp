#include "converter/occt/occt_util.h"

#include <BRepCheck.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepCheck_ListOfStatus.hxx>
#include <BRepCheck_Result.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>

#include <sstream>
#include <vector>

namespace subd2nurbs::occt::detail {

std::string occt_message(const Standard_Failure& failure) {
  const char* text = failure.GetMessageString();
  std::string message = text != nullptr ? text : "";
  if (message.empty()) message = failure.DynamicType()->Name();
  return message;
}

namespace {

const char* type_name(TopAbs_ShapeEnum type) {
  switch (type) {
    case TopAbs_VERTEX: return "vertex";
    case TopAbs_EDGE: return "edge";
    case TopAbs_WIRE: return "wire";
    case TopAbs_FACE: return "face";
    case TopAbs_SHELL: return "shell";
    case TopAbs_SOLID: return "solid";
    case TopAbs_COMPSOLID: return "compsolid";
    case TopAbs_COMPOUND: return "compound";
    default: return "shape";
  }
}

/// "InvalidCurveOnSurface" for BRepCheck_InvalidCurveOnSurface (BRepCheck::Print writes the
/// enumerator's name plus a newline).
std::string status_name(BRepCheck_Status status) {
  std::ostringstream out;
  BRepCheck::Print(status, out);
  std::string name = out.str();
  while (!name.empty() && (name.back() == '\n' || name.back() == ' ')) name.pop_back();
  const std::string prefix = "BRepCheck_";
  if (name.compare(0, prefix.size(), prefix) == 0) name.erase(0, prefix.size());
  return name;
}

}  // namespace

bool check_shape(const TopoDS_Shape& shape, std::string& message, const ShapeNamer& namer,
                 int max_lines) {
  message.clear();
  BRepCheck_Analyzer analyzer(shape, /*GeomControls=*/Standard_True);
  if (analyzer.IsValid()) return true;

  // The analyzer keeps one BRepCheck_Result per distinct sub-shape. A result has statuses of
  // the sub-shape on its own, plus statuses "in context" of an ancestor (an edge is checked
  // against each face it bounds: InvalidCurveOnSurface is reported with the face as context).
  TopTools_IndexedMapOfShape all;
  TopExp::MapShapes(shape, all);
  // Default names number sub-shapes per type, in TopExp::MapShapes order; maps built once.
  std::vector<TopTools_IndexedMapOfShape> by_type(TopAbs_SHAPE);
  auto name_of = [&](const TopoDS_Shape& s) {
    if (namer) {
      std::string name = namer(s);
      if (!name.empty()) return name;
    }
    TopTools_IndexedMapOfShape& of_type = by_type[s.ShapeType()];
    if (of_type.IsEmpty()) TopExp::MapShapes(shape, s.ShapeType(), of_type);
    return std::string(type_name(s.ShapeType())) + " #" + std::to_string(of_type.FindIndex(s));
  };

  int total = 0;
  auto add = [&](const TopoDS_Shape& s, const BRepCheck_ListOfStatus& statuses,
                 const TopoDS_Shape* context) {
    for (BRepCheck_ListOfStatus::Iterator it(statuses); it.More(); it.Next()) {
      if (it.Value() == BRepCheck_NoError) continue;
      if (total++ >= max_lines) continue;  // only counted
      message += name_of(s) + ": " + status_name(it.Value());
      if (context != nullptr && !context->IsSame(s)) message += " on " + name_of(*context);
      message += "\n";
    }
  };
  for (int i = 1; i <= all.Extent(); ++i) {
    const TopoDS_Shape& sub = all(i);
    Handle(BRepCheck_Result) result;
    try {
      result = analyzer.Result(sub);
    } catch (const Standard_Failure&) {
      continue;  // no result for this sub-shape (e.g. the compound on top)
    }
    if (result.IsNull()) continue;
    add(sub, result->Status(), nullptr);
    for (result->InitContextIterator(); result->MoreShapeInContext();
         result->NextShapeInContext()) {
      const TopoDS_Shape context = result->ContextualShape();
      add(sub, result->StatusOnShape(), &context);
    }
  }
  if (total == 0) message = "BRepCheck_Analyzer: invalid (no detailed status)\n";
  if (total > max_lines) message += "... and " + std::to_string(total - max_lines) + " more\n";
  return false;
}

std::mutex& exchange_mutex() {
  static std::mutex mutex;
  return mutex;
}

QuietMessages::QuietMessages() {
  const Handle(Message_Messenger)& messenger = Message::DefaultMessenger();
  saved_ = messenger->Printers();
  messenger->ChangePrinters().Clear();
}

QuietMessages::~QuietMessages() {
  const Handle(Message_Messenger)& messenger = Message::DefaultMessenger();
  messenger->ChangePrinters().Clear();
  for (Message_SequenceOfPrinters::Iterator it(saved_); it.More(); it.Next())
    messenger->AddPrinter(it.Value());
}

void StaticSettings::set(const char* stage, const std::string& name, const std::string& value) {
  guarded(stage, -1, [&] {
    if (!Interface_Static::IsPresent(name.c_str()))
      throw ExportError(stage, -1, "OCCT setting '" + name + "' does not exist");
    const std::string previous = Interface_Static::CVal(name.c_str());
    if (!Interface_Static::SetCVal(name.c_str(), value.c_str()))
      throw ExportError(stage, -1, "OCCT setting '" + name + "' refuses the value '" + value + "'");
    saved_.emplace_back(name, previous);
  });
}

StaticSettings::~StaticSettings() {
  // Newest first, so that setting one name twice still ends at the oldest value.
  for (auto it = saved_.rbegin(); it != saved_.rend(); ++it) {
    try {
      Interface_Static::SetCVal(it->first.c_str(), it->second.c_str());
    } catch (const Standard_Failure&) {
      // Nothing sensible to do in a destructor; the value was readable a moment ago.
    }
  }
}

}  // namespace subd2nurbs::occt::detail
