// Reading one number out of JSON text the converter wrote (header-only): enough for tests that
// check a report's member without a JSON library.
#pragma once

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

namespace subd2nurbs::testing {

/// The number after `"key": ` following the keys of `path` in order, in JSON text (NaN if absent).
inline double json_number(const std::string& text, const std::vector<std::string>& path) {
  size_t at = 0;
  for (const std::string& key : path) {
    at = text.find("\"" + key + "\": ", at);
    if (at == std::string::npos) return std::nan("");
    at += key.size() + 4;
  }
  return std::strtod(text.c_str() + at, nullptr);
}

}  // namespace subd2nurbs::testing
