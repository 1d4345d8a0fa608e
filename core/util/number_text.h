// Numbers in messages: the shortest %g text that reads back as the same double, so that a
// value just beyond a limit never prints as the limit itself ("1000000000000000.1", not
// "1e+15"); short values stay short ("1e+200", "0.5").
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

namespace subd2nurbs {

inline std::string exact_number_text(double x) {
  char buffer[40];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, x);
    if (std::strtod(buffer, nullptr) == x) break;
  }
  return buffer;
}

}  // namespace subd2nurbs
