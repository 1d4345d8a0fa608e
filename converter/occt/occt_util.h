// Internal helpers of the OCCT front end (not part of its API): exception guards and the
// BRepCheck report. Only converter/occt/*.cpp include this.
#pragma once

#include <Standard_Failure.hxx>
#include <TopoDS_Shape.hxx>

#include <Message_SequenceOfPrinters.hxx>

#include <functional>
#include <mutex>
#include <string>
#include <vector>
#include <utility>

#include "converter/occt/export_error.h"

namespace subd2nurbs::occt::detail {

/// OCCT's message for an exception; some exceptions carry none, then the exception's type name
/// (e.g. "Standard_ConstructionError") is the best description there is.
std::string occt_message(const Standard_Failure& failure);

/// Runs f() and turns an OCCT exception (Standard_Failure, which does NOT derive from
/// std::exception) into ExportError{stage, patch}. Other exceptions pass unchanged.
template <class F>
auto guarded(const char* stage, int patch, F&& f) -> decltype(f()) {
  try {
    return std::forward<F>(f)();
  } catch (const Standard_Failure& failure) {
    throw ExportError(stage, patch, occt_message(failure));
  }
}

/// Names a sub-shape in check messages (e.g. "face 12 (patch 12)"); empty: use the default
/// "face #N" numbering of TopExp::MapShapes.
using ShapeNamer = std::function<std::string(const TopoDS_Shape&)>;

/// Runs BRepCheck_Analyzer (with geometric checks) on `shape`. Returns true when it is valid;
/// otherwise `message` lists the findings, one "SUBSHAPE: STATUS[ on CONTEXT]" per line
/// (at most `max_lines`, then a count of the rest).
bool check_shape(const TopoDS_Shape& shape, std::string& message, const ShapeNamer& namer = {},
                 int max_lines = 20);

/// Serializes OCCT data exchange (STEP / IGES reading and writing): their settings
/// (Interface_Static) and the default messenger are process-wide.
std::mutex& exchange_mutex();

/// Silences OCCT's default messenger while alive. The STEP and IGES translators report their
/// statistics ("Statistics on Transfer (Write)", "Step File Name : ... Write Done") on
/// std::cout through Message::DefaultMessenger(), which would corrupt a --json stdout. Hold
/// exchange_mutex() while one exists.
class QuietMessages {
 public:
  QuietMessages();
  ~QuietMessages();
  QuietMessages(const QuietMessages&) = delete;
  QuietMessages& operator=(const QuietMessages&) = delete;

 private:
  Message_SequenceOfPrinters saved_;
};

/// Sets Interface_Static values and restores the previous ones when destroyed (also during
/// stack unwinding). Hold exchange_mutex() while one exists.
class StaticSettings {
 public:
  StaticSettings() = default;
  ~StaticSettings();
  StaticSettings(const StaticSettings&) = delete;
  StaticSettings& operator=(const StaticSettings&) = delete;

  /// Sets `name` to `value` (enum statics take the enumerator's text, e.g. "Off", "AP214IS").
  /// \throw ExportError(stage) if the setting does not exist or refuses the value.
  void set(const char* stage, const std::string& name, const std::string& value);

 private:
  std::vector<std::pair<std::string, std::string>> saved_;  ///< name, previous CVal
};

}  // namespace subd2nurbs::occt::detail
