#include "converter/pipeline/text.h"

#include <cstdio>

namespace subd2nurbs::pipeline {

std::string short_number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", x);
  return buffer;
}

}  // namespace subd2nurbs::pipeline
