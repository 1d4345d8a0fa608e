// The one error of a conversion setting that cannot be used, shared by the conversion's and the
// resource limits' rules (conversion.h validate, resources.h).
#pragma once

#include <stdexcept>
#include <string>

#include "core/util/error.h"

namespace subd2nurbs::pipeline {

/// A setting that cannot be used: `setting` names it as the Python module spells it (level,
/// tolerance, radial_steps, polar_lambda, fair, ...), `rule` says what it must be ("must be 1
/// or 2"), in words every front end shows as they are; each spells the setting its own way (the
/// CLI's flag, the workbench's property). what() is "<setting> <rule>".
class SettingsError : public Error {
 public:
  SettingsError(const std::string& setting, const std::string& rule)
      : Error(ErrorKind::Settings, setting + " " + rule), setting_(setting), rule_(rule) {}
  const std::string& setting() const { return setting_; }
  const std::string& rule() const { return rule_; }

 private:
  std::string setting_, rule_;
};

}  // namespace subd2nurbs::pipeline
