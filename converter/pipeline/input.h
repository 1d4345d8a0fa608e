// What every front end converts from a file: the cage read by its format (io/cage_reader.h),
// validated, with the reader's and the validation's warnings as text. The command line's
// subcommands and the Python module's read_cage load through here, so that a file gives the
// same cage and the same warnings everywhere.
#pragma once

#include <string>
#include <vector>

#include "core/refine/refiner.h"
#include "io/obj_reader.h"
#include "io/usd_reader.h"

namespace subd2nurbs::pipeline {

struct LoadedInput {
  LoadedCage cage;
  SubdivLevel level;
  std::vector<std::string> warnings;  ///< "FILE:LINE: warning: ..." (format_diagnostic)

  std::vector<Point3> positions() const {
    return std::vector<Point3>(cage.input.positions.begin(), cage.input.positions.end());
  }
};

/// Reads and validates a cage; `usd` applies to USD files (the variants to select).
/// \throw InputError for an unreadable or invalid cage
LoadedInput load_input(const std::string& path, const UsdReadOptions& usd = {});
/// Validates a cage already read (its warnings included). \throw InputError for an invalid cage
LoadedInput load_input(LoadedCage cage);

}  // namespace subd2nurbs::pipeline
