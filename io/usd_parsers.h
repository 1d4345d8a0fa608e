// The two USD encodings parsed into the layer model (io/usd_layer.h). Internal to io/: the
// public entry points are in io/usd_reader.h.
#pragma once

#include <string>
#include <string_view>

#include "io/usd_layer.h"

namespace subd2nurbs::usd {

/// usda text (io/usda_parser.cpp). \throw InputError naming `name` and the line.
void parse_usda(std::string_view text, const std::string& name, const Limits& limits, Layer& layer);

/// The binary crate ("PXR-USDC", io/usd_crate.cpp). \throw InputError naming `name` and what is
/// wrong (section, offset, index) when the file is truncated, inconsistent or too large.
void parse_usdc(std::string_view bytes, const std::string& name, const Limits& limits, Layer& layer);

}  // namespace subd2nurbs::usd
