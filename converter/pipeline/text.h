// Text helpers of the reports and messages: JSON strings and numbers, short numbers.
#pragma once

#include <string>

#include "core/util/point3.h"

namespace subd2nurbs::pipeline {

/// A quoted, escaped JSON string (JsonWriter::quoted, io/json_writer.h).
std::string json_string(const std::string& s);
/// A JSON number with "%.17g" (exact as an IEEE double), or null when not finite (as a report's
/// JsonWriter writes it).
std::string json_number(double x);
/// [x, y, z] with json_number.
std::string json_point(const Point3& p);

/// A short number for messages ("%.3g").
std::string short_number(double x);

}  // namespace subd2nurbs::pipeline
