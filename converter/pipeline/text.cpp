#include "converter/pipeline/text.h"

#include <cmath>
#include <cstdio>

namespace subd2nurbs::pipeline {

std::string json_string(const std::string& s) {
  std::string r = "\"";
  for (const unsigned char c : s) {
    switch (c) {
      case '"': r += "\\\""; break;
      case '\\': r += "\\\\"; break;
      case '\n': r += "\\n"; break;
      case '\r': r += "\\r"; break;
      case '\t': r += "\\t"; break;
      default:
        if (c < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
          r += buffer;
        } else {
          r += static_cast<char>(c);
        }
    }
  }
  return r + "\"";
}

std::string json_number(double x) {
  if (!std::isfinite(x)) return "null";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
}

std::string json_point(const Point3& p) {
  return "[" + json_number(p[0]) + ", " + json_number(p[1]) + ", " + json_number(p[2]) + "]";
}

std::string short_number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", x);
  return buffer;
}

}  // namespace subd2nurbs::pipeline
