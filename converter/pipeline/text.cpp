#include "converter/pipeline/text.h"

#include <cstdio>

#include "io/json_writer.h"

namespace subd2nurbs::pipeline {

std::string json_string(const std::string& s) { return JsonWriter::quoted(s); }

std::string json_number(double x) { return JsonWriter::report_number(x); }

std::string json_point(const Point3& p) {
  return "[" + json_number(p[0]) + ", " + json_number(p[1]) + ", " + json_number(p[2]) + "]";
}

std::string short_number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", x);
  return buffer;
}

}  // namespace subd2nurbs::pipeline
