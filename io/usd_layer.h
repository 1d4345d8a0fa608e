// The part of a USD layer a cage reader needs, as both encodings parse it (io/usda_parser.cpp for
// text, io/usd_crate.cpp for the binary crate): a tree of prim specs with their attributes,
// variant sets, internal references and the layer's metadata. Values are kept as doubles or
// strings whatever their USD type (ints up to 2^53 are exact), with the type's name. Composition
// (variants, references, transforms) and the mesh mapping are in io/usd_reader.cpp.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace subd2nurbs::usd {

/// A value: numbers (flattened: a point3f[] of n points holds 3n numbers, `width` 3), or
/// strings (token, string, asset), or nothing (None / a value block).
struct Value {
  enum class Kind { Empty, Numbers, Strings } kind = Kind::Empty;
  std::vector<double> numbers;
  std::vector<std::string> strings;
  int width = 1;       ///< numbers per element (3 for a point, 4 for a quaternion, 16 for a matrix)
  bool array = false;  ///< an array type ("int[]") rather than a scalar
};

/// Hard limits every parser checks before it allocates or recurses.
struct Limits {
  long max_prims = 1000000;          ///< prim, variant and attribute specs of a layer
  long max_values = 200000000;       ///< numbers and strings all values together
  int max_depth = 200;               ///< nesting of prims, variants, brackets, dictionaries
  long max_expanded_prims = 2000000; ///< prims after references and variants are expanded
};

struct Attribute {
  std::string type_name;  ///< "int[]", "point3f[]", "token", ...
  bool has_default = false;
  Value default_value;
  std::vector<std::pair<double, Value>> samples;  ///< time samples in file order
  int line = 0;                                    ///< usda line (0 for usdc)
};

enum class Specifier { Def, Over, Class };

struct PrimSpec;

struct VariantSet {
  std::string name;
  std::vector<std::pair<std::string, std::unique_ptr<PrimSpec>>> variants;
};

struct PrimSpec {
  std::string name;
  Specifier specifier = Specifier::Over;
  std::string type_name;
  int line = 0;
  std::vector<std::pair<std::string, Attribute>> attributes;
  std::vector<std::unique_ptr<PrimSpec>> children;
  std::vector<VariantSet> variant_sets;
  std::map<std::string, std::string> variant_selection;
  std::vector<std::string> internal_references;  ///< prim paths in this layer ("/A/B")
  std::vector<std::string> external_references;  ///< asset paths (references and payloads)
  bool instanceable = false;
  int active = -1;  ///< `active` metadata: -1 not authored, 0 false (the prim and its subtree are not read), 1 true

  PrimSpec* child(const std::string& child_name) const {
    for (const auto& c : children)
      if (c->name == child_name) return c.get();
    return nullptr;
  }
  PrimSpec& child_or_add(const std::string& child_name) {
    if (PrimSpec* c = child(child_name)) return *c;
    children.push_back(std::make_unique<PrimSpec>());
    children.back()->name = child_name;
    return *children.back();
  }
  const Attribute* attribute(const std::string& attr_name) const {
    for (const auto& [n, a] : attributes)
      if (n == attr_name) return &a;
    return nullptr;
  }
  Attribute& attribute_or_add(const std::string& attr_name) {
    for (auto& [n, a] : attributes)
      if (n == attr_name) return a;
    attributes.emplace_back(attr_name, Attribute{});
    return attributes.back().second;
  }
  VariantSet& variant_set_or_add(const std::string& set_name) {
    for (VariantSet& s : variant_sets)
      if (s.name == set_name) return s;
    variant_sets.push_back(VariantSet{set_name, {}});
    return variant_sets.back();
  }
};

struct Layer {
  PrimSpec root;  ///< the pseudo-root: its children are the layer's root prims
  double meters_per_unit = 0;  ///< 0: not authored
  std::string up_axis;         ///< "" when not authored
  std::string default_prim;
  std::string encoding;        ///< "usda" or "usdc"
  std::string version;         ///< "1.0" for text, the crate's version ("0.8.0")
  std::vector<std::string> notes;  ///< things read but not used (sublayers, ...)
};

}  // namespace subd2nurbs::usd
