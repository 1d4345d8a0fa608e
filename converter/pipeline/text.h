// Text helpers of the messages (JSON is written with io/json_writer.h).
#pragma once

#include <string>

namespace subd2nurbs::pipeline {

/// A short number for messages ("%.3g").
std::string short_number(double x);

}  // namespace subd2nurbs::pipeline
