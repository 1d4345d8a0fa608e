// The binary USD "crate" format (usdc), read into the layer model of io/usd_layer.h. Written
// from the format as OpenUSD's sources describe it (pxr/usd/usd/crateFile.cpp, integerCoding.cpp,
// pxr/base/tf/fastCompression.cpp); no code copied.
//
// Layout: an 88-byte bootstrap ("PXR-USDC", version major.minor.patch, the table of contents'
// offset), the table of contents (named sections: TOKENS, STRINGS, FIELDS, FIELDSETS, PATHS,
// SPECS), and the values the fields point at. A field is (token, value rep); a value rep is 64
// bits: array / inlined / compressed flags, an 8-bit type and a 48-bit payload (an inlined value
// or a file offset). Versions 0.4.0 and later compress the structural sections: LZ4 blocks
// (TfFastCompression: a chunk count byte, then one block or int32-sized chunks) of integer
// arrays coded as deltas (a common delta, 2-bit size codes, then 8/16/32-bit or 16/32/64-bit
// values). Every count is checked against the bytes present before anything is allocated.
#include <lz4.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "io/input_error.h"
#include "io/input_file.h"
#include "io/usd_parsers.h"

namespace subd2nurbs::usd {

namespace {

enum Type : int {
  kBool = 1, kUChar, kInt, kUInt, kInt64, kUInt64, kHalf, kFloat, kDouble, kString, kToken, kAssetPath,
  kMatrix2d, kMatrix3d, kMatrix4d, kQuatd, kQuatf, kQuath, kVec2d, kVec2f, kVec2h, kVec2i, kVec3d, kVec3f,
  kVec3h, kVec3i, kVec4d, kVec4f, kVec4h, kVec4i, kDictionary, kTokenListOp, kStringListOp, kPathListOp,
  kReferenceListOp, kIntListOp, kInt64ListOp, kUIntListOp, kUInt64ListOp, kPathVector, kTokenVector,
  kSpecifier, kPermission, kVariability, kVariantSelectionMap, kTimeSamples, kPayload, kDoubleVector,
  kLayerOffsetVector, kStringVector, kValueBlock, kValue, kUnregisteredValue, kUnregisteredValueListOp,
  kPayloadListOp, kTimeCode, kPathExpression
};

enum SpecType : std::uint32_t { kAttributeSpec = 1, kPrimSpec = 6, kPseudoRootSpec = 7, kVariantSpec = 10, kVariantSetSpec = 11 };

constexpr std::uint64_t kArrayBit = 1ull << 63, kInlinedBit = 1ull << 62, kCompressedBit = 1ull << 61;
constexpr std::uint64_t kPayloadMask = (1ull << 48) - 1;
constexpr std::size_t kMinCompressedArray = 16;

double half_to_double(std::uint16_t h) {
  const int sign = (h >> 15) & 1, exponent = (h >> 10) & 31, mantissa = h & 1023;
  double v;
  if (exponent == 0) v = std::ldexp(mantissa, -24);
  else if (exponent == 31) v = mantissa ? std::nan("") : INFINITY;
  else v = std::ldexp(mantissa + 1024, exponent - 25);
  return sign ? -v : v;
}

/// Element layout of a numeric type: scalar kind (0 int, 1 uint, 2 float, 3 double, 4 half,
/// 5 int64, 6 uint64, 7 bool/uchar) and components; components 0 for non-numeric types.
struct Layout {
  int scalar = 0;
  int components = 0;
};

Layout layout(int type) {
  switch (type) {
    case kBool: case kUChar: return {7, 1};
    case kInt: return {0, 1};
    case kUInt: return {1, 1};
    case kInt64: return {5, 1};
    case kUInt64: return {6, 1};
    case kHalf: return {4, 1};
    case kFloat: return {2, 1};
    case kDouble: case kTimeCode: return {3, 1};
    case kMatrix2d: return {3, 4};
    case kMatrix3d: return {3, 9};
    case kMatrix4d: return {3, 16};
    case kQuatd: return {3, 4};
    case kQuatf: return {2, 4};
    case kQuath: return {4, 4};
    case kVec2d: return {3, 2};
    case kVec2f: return {2, 2};
    case kVec2h: return {4, 2};
    case kVec2i: return {0, 2};
    case kVec3d: return {3, 3};
    case kVec3f: return {2, 3};
    case kVec3h: return {4, 3};
    case kVec3i: return {0, 3};
    case kVec4d: return {3, 4};
    case kVec4f: return {2, 4};
    case kVec4h: return {4, 4};
    case kVec4i: return {0, 4};
    default: return {0, 0};
  }
}

int scalar_bytes(int scalar) {
  switch (scalar) {
    case 7: return 1;
    case 4: return 2;
    case 0: case 1: case 2: return 4;
    default: return 8;
  }
}

bool is_quat(int type) { return type == kQuatd || type == kQuatf || type == kQuath; }

class Crate {
 public:
  Crate(std::string_view bytes, const std::string& name, const Limits& limits, Layer& layer)
      : bytes_(bytes), name_(name), limits_(limits), layer_(layer) {}

  void parse() {
    read_bootstrap();
    read_toc();
    read_tokens();
    read_strings();
    read_fields();
    read_fieldsets();
    read_paths();
    read_specs();
    build_layer();
  }

 private:
  [[noreturn]] void fail(const std::string& message) const {
    throw InputError(name_, 0, "corrupt USD crate file: " + message);
  }

  // --- bytes ---------------------------------------------------------------------------------

  void need(std::uint64_t offset, std::uint64_t size, const char* what) const {
    if (offset > bytes_.size() || size > bytes_.size() - offset)
      fail(std::string(what) + " needs " + std::to_string(size) + " bytes at offset " + std::to_string(offset) +
           ", beyond the end of the file (" + std::to_string(bytes_.size()) + " bytes)");
  }

  template <class T>
  T get(std::uint64_t& offset, const char* what) const {
    need(offset, sizeof(T), what);
    T value;
    std::memcpy(&value, bytes_.data() + offset, sizeof(T));
    offset += sizeof(T);
    return value;
  }

  /// A count of elements of `element_bytes` each that must fit in the bytes from `offset`
  /// (`ratio` > 1 allows compressed data) and in the value limit.
  void check_count(std::uint64_t count, std::uint64_t offset, double element_bytes, const char* what) const {
    const double available = offset <= bytes_.size() ? static_cast<double>(bytes_.size() - offset) : 0;
    if (static_cast<double>(count) * element_bytes > available + 64 || count > static_cast<std::uint64_t>(limits_.max_values))
      fail(std::string(what) + " claims " + std::to_string(count) + " elements, more than the " +
           std::to_string(bytes_.size()) + "-byte file can hold");
  }

  /// TfFastCompression: one LZ4 block (first byte 0) or N int32-sized chunks (first byte N).
  std::vector<char> decompress(std::uint64_t offset, std::uint64_t size, std::uint64_t expected, const char* what) const {
    need(offset, size, what);
    if (size < 1) fail(std::string(what) + ": empty compressed block");
    if (expected > 255 * size + 64 || expected > (std::uint64_t{1} << 33))
      fail(std::string(what) + ": " + std::to_string(expected) + " bytes cannot come from " + std::to_string(size) +
           " compressed bytes");
    std::vector<char> out(expected);
    const char* src = bytes_.data() + offset;
    const int chunks = static_cast<signed char>(src[0]);
    std::uint64_t produced = 0;
    if (chunks == 0) {
      if (size - 1 > 0x7fffffff || expected > 0x7fffffff) fail(std::string(what) + ": block too large");
      const int n = LZ4_decompress_safe(src + 1, out.data(), static_cast<int>(size - 1), static_cast<int>(expected));
      if (n < 0) fail(std::string(what) + ": LZ4 data is corrupt");
      produced = static_cast<std::uint64_t>(n);
    } else if (chunks > 0) {
      std::uint64_t at = 1;
      for (int c = 0; c < chunks; ++c) {
        if (at + 4 > size) fail(std::string(what) + ": chunk header beyond the block");
        std::int32_t chunk;
        std::memcpy(&chunk, src + at, 4);
        at += 4;
        if (chunk < 0 || static_cast<std::uint64_t>(chunk) > size - at) fail(std::string(what) + ": chunk beyond the block");
        const std::uint64_t room = std::min<std::uint64_t>(expected - produced, 0x7e000000);
        const int n = LZ4_decompress_safe(src + at, out.data() + produced, chunk, static_cast<int>(room));
        if (n < 0) fail(std::string(what) + ": LZ4 data is corrupt");
        produced += static_cast<std::uint64_t>(n);
        at += static_cast<std::uint64_t>(chunk);
      }
    } else {
      fail(std::string(what) + ": negative chunk count");
    }
    out.resize(produced);
    return out;
  }

  /// Compressed integers (uint64 compressed size, then the compressed block) of `count` 4- or
  /// 8-byte integers; returned widened to int64 (the bits of unsigned values kept).
  template <class Int>
  std::vector<Int> compressed_ints(std::uint64_t& offset, std::uint64_t count, const char* what) const {
    const std::uint64_t size = get<std::uint64_t>(offset, what);
    need(offset, size, what);
    // Each integer takes at least 2 bits once decoded; LZ4 expands at most ~255 times.
    if (count > (255 * size + 64) * 4 || count > static_cast<std::uint64_t>(limits_.max_values))
      fail(std::string(what) + " claims " + std::to_string(count) + " integers in " + std::to_string(size) + " bytes");
    std::vector<Int> out;
    if (count == 0) {
      offset += size;
      return out;
    }
    const std::uint64_t max_encoded = sizeof(Int) + (count * 2 + 7) / 8 + count * sizeof(Int);
    const std::vector<char> data = decompress(offset, size, std::min<std::uint64_t>(max_encoded, 255 * size + 64), what);
    offset += size;
    using SInt = std::make_signed_t<Int>;
    using Small = std::conditional_t<sizeof(Int) == 4, std::int8_t, std::int16_t>;
    using Medium = std::conditional_t<sizeof(Int) == 4, std::int16_t, std::int32_t>;
    const std::uint64_t codes_bytes = (count * 2 + 7) / 8;
    if (data.size() < sizeof(SInt) + codes_bytes) fail(std::string(what) + ": integer codes truncated");
    SInt common;
    std::memcpy(&common, data.data(), sizeof common);
    const char* codes = data.data() + sizeof(SInt);
    std::uint64_t at = sizeof(SInt) + codes_bytes;
    out.resize(count);
    SInt previous = 0;
    for (std::uint64_t i = 0; i < count; ++i) {
      const int code = (static_cast<unsigned char>(codes[i / 4]) >> (2 * (i % 4))) & 3;
      SInt delta = common;
      auto take = [&](auto dummy) {
        using T = decltype(dummy);
        if (at + sizeof(T) > data.size()) fail(std::string(what) + ": integer data truncated");
        T v;
        std::memcpy(&v, data.data() + at, sizeof v);
        at += sizeof v;
        return static_cast<SInt>(v);
      };
      if (code == 1) delta = take(Small{});
      else if (code == 2) delta = take(Medium{});
      else if (code == 3) delta = take(SInt{});
      previous = static_cast<SInt>(static_cast<std::make_unsigned_t<SInt>>(previous) +
                                   static_cast<std::make_unsigned_t<SInt>>(delta));
      out[i] = static_cast<Int>(previous);
    }
    return out;
  }

  // --- structure -----------------------------------------------------------------------------

  void read_bootstrap() {
    if (bytes_.size() < 88) fail("the file is shorter than the 88-byte crate header");
    if (bytes_.substr(0, 8) != "PXR-USDC") fail("no 'PXR-USDC' header");
    major_ = static_cast<unsigned char>(bytes_[8]);
    minor_ = static_cast<unsigned char>(bytes_[9]);
    patch_ = static_cast<unsigned char>(bytes_[10]);
    layer_.encoding = "usdc";
    layer_.version = std::to_string(major_) + "." + std::to_string(minor_) + "." + std::to_string(patch_);
    if (major_ != 0 || minor_ < 4 || minor_ > 12)
      throw InputError(name_, 0, "USD crate version " + layer_.version +
                                     " is not read (versions 0.4.0 to 0.12.x are; re-save the file with a current USD)");
    std::uint64_t at = 16;
    toc_ = get<std::uint64_t>(at, "the table of contents' offset");
    if (toc_ >= bytes_.size()) fail("the table of contents' offset " + std::to_string(toc_) + " is beyond the end of the file (truncated?)");
  }

  struct Section {
    std::uint64_t start = 0, size = 0;
    bool present = false;
  };
  Section tokens_s_, strings_s_, fields_s_, fieldsets_s_, paths_s_, specs_s_;

  void read_toc() {
    std::uint64_t at = toc_;
    const std::uint64_t n = get<std::uint64_t>(at, "the table of contents");
    check_count(n, at, 32, "the table of contents");
    for (std::uint64_t i = 0; i < n; ++i) {
      need(at, 32, "a section of the table of contents");
      std::string section_name(bytes_.data() + at, strnlen(bytes_.data() + at, 16));
      at += 16;
      Section s;
      s.start = get<std::uint64_t>(at, "a section's start");
      s.size = get<std::uint64_t>(at, "a section's size");
      s.present = true;
      need(s.start, s.size, ("section " + section_name).c_str());
      if (section_name == "TOKENS") tokens_s_ = s;
      else if (section_name == "STRINGS") strings_s_ = s;
      else if (section_name == "FIELDS") fields_s_ = s;
      else if (section_name == "FIELDSETS") fieldsets_s_ = s;
      else if (section_name == "PATHS") paths_s_ = s;
      else if (section_name == "SPECS") specs_s_ = s;
    }
    for (const auto* s : {&tokens_s_, &fields_s_, &fieldsets_s_, &paths_s_, &specs_s_})
      if (!s->present) fail("a structural section (TOKENS, FIELDS, FIELDSETS, PATHS or SPECS) is missing");
  }

  void read_tokens() {
    std::uint64_t at = tokens_s_.start;
    const std::uint64_t count = get<std::uint64_t>(at, "TOKENS");
    const std::uint64_t raw = get<std::uint64_t>(at, "TOKENS");
    const std::uint64_t packed = get<std::uint64_t>(at, "TOKENS");
    if (count > raw) fail("TOKENS claims " + std::to_string(count) + " tokens in " + std::to_string(raw) + " bytes");
    check_count(count, at, 0, "TOKENS");
    const std::vector<char> chars = decompress(at, packed, raw, "TOKENS");
    if (chars.size() != raw) fail("TOKENS decompressed to " + std::to_string(chars.size()) + " bytes, not " + std::to_string(raw));
    tokens_.reserve(count);
    std::size_t p = 0;
    while (tokens_.size() < count) {
      if (p >= chars.size()) fail("TOKENS holds fewer than the " + std::to_string(count) + " tokens it claims");
      const char* start = chars.data() + p;
      const std::size_t len = strnlen(start, chars.size() - p);
      tokens_.emplace_back(start, len);
      p += len + 1;
    }
  }

  const std::string& token(std::uint64_t i, const char* what) const {
    if (i >= tokens_.size()) fail(std::string(what) + ": token " + std::to_string(i) + " of " + std::to_string(tokens_.size()));
    return tokens_[i];
  }

  const std::string& string_at(std::uint64_t i, const char* what) const {
    if (i >= strings_.size()) fail(std::string(what) + ": string " + std::to_string(i) + " of " + std::to_string(strings_.size()));
    return token(strings_[i], what);
  }

  void read_strings() {
    if (!strings_s_.present) return;
    std::uint64_t at = strings_s_.start;
    const std::uint64_t count = get<std::uint64_t>(at, "STRINGS");
    check_count(count, at, 4, "STRINGS");
    strings_.resize(count);
    for (auto& s : strings_) {
      s = get<std::uint32_t>(at, "STRINGS");
      token(s, "STRINGS");
    }
  }

  void read_fields() {
    std::uint64_t at = fields_s_.start;
    const std::uint64_t count = get<std::uint64_t>(at, "FIELDS");
    const std::vector<std::uint32_t> names = compressed_ints<std::uint32_t>(at, count, "FIELDS (names)");
    const std::uint64_t reps_size = get<std::uint64_t>(at, "FIELDS (values)");
    const std::vector<char> reps = decompress(at, reps_size, count * 8, "FIELDS (values)");
    if (reps.size() != count * 8) fail("FIELDS: " + std::to_string(count) + " value reps expected");
    fields_.resize(count);
    for (std::uint64_t i = 0; i < count; ++i) {
      fields_[i].name = &token(names[i], "FIELDS");
      std::memcpy(&fields_[i].rep, reps.data() + 8 * i, 8);
    }
  }

  void read_fieldsets() {
    std::uint64_t at = fieldsets_s_.start;
    const std::uint64_t count = get<std::uint64_t>(at, "FIELDSETS");
    fieldsets_ = compressed_ints<std::uint32_t>(at, count, "FIELDSETS");
    if (!fieldsets_.empty() && fieldsets_.back() != ~0u) fail("FIELDSETS is not terminated");
    for (std::uint32_t f : fieldsets_)
      if (f != ~0u && f >= fields_.size())
        fail("FIELDSETS names field " + std::to_string(f) + " of " + std::to_string(fields_.size()));
  }

  struct PathNode {
    std::int64_t parent = -2;  ///< -2 unassigned, -1 the root
    const std::string* element = nullptr;
    bool property = false;
    int depth = 0;
  };

  void read_paths() {
    std::uint64_t at = paths_s_.start;
    const std::uint64_t count = get<std::uint64_t>(at, "PATHS");
    const std::uint64_t encoded = get<std::uint64_t>(at, "PATHS");
    check_count(count, at, 0.01, "PATHS");
    if (count > static_cast<std::uint64_t>(limits_.max_prims) * 4) fail("PATHS claims " + std::to_string(count) + " paths");
    const auto indexes = compressed_ints<std::uint32_t>(at, encoded, "PATHS (indexes)");
    const auto elements = compressed_ints<std::int32_t>(at, encoded, "PATHS (elements)");
    const auto jumps = compressed_ints<std::int32_t>(at, encoded, "PATHS (jumps)");
    paths_.assign(count, PathNode{});
    if (encoded == 0) return;
    std::vector<char> visited(encoded, 0);
    std::vector<std::pair<std::uint64_t, std::int64_t>> stack{{0, -1}};
    bool root_done = false;
    while (!stack.empty()) {
      auto [cur, parent] = stack.back();
      stack.pop_back();
      while (true) {
        if (cur >= encoded) fail("PATHS jumps to entry " + std::to_string(cur) + " of " + std::to_string(encoded));
        if (visited[cur]) fail("PATHS visits entry " + std::to_string(cur) + " twice (a cyclic path table)");
        visited[cur] = 1;
        const std::uint32_t p = indexes[cur];
        if (p >= count) fail("PATHS names path " + std::to_string(p) + " of " + std::to_string(count));
        if (paths_[p].parent != -2) fail("PATHS defines path " + std::to_string(p) + " twice");
        PathNode& node = paths_[p];
        if (parent == -1) {
          if (root_done) fail("PATHS has a second root");
          root_done = true;
          node.parent = -1;
        } else {
          const std::int32_t e = elements[cur];
          node.parent = parent;
          node.property = e < 0;
          node.element = &token(e < 0 ? -static_cast<std::int64_t>(e) : e, "PATHS");
          node.depth = paths_[static_cast<std::size_t>(parent)].depth + 1;
          if (node.depth > limits_.max_depth) fail("a path nests deeper than " + std::to_string(limits_.max_depth) + " levels");
        }
        const std::int32_t jump = jumps[cur];
        const bool child = jump > 0 || jump == -1, sibling = jump >= 0;
        if (child && sibling) stack.emplace_back(cur + static_cast<std::uint64_t>(jump), parent);
        if (child) parent = p;
        if (!child && !sibling) break;
        ++cur;
      }
    }
  }

  struct Spec {
    std::uint32_t path, fieldset, type;
  };

  void read_specs() {
    std::uint64_t at = specs_s_.start;
    const std::uint64_t count = get<std::uint64_t>(at, "SPECS");
    if (count > static_cast<std::uint64_t>(limits_.max_prims) * 4) fail("SPECS claims " + std::to_string(count) + " specs");
    const auto paths = compressed_ints<std::uint32_t>(at, count, "SPECS (paths)");
    const auto sets = compressed_ints<std::uint32_t>(at, count, "SPECS (field sets)");
    const auto types = compressed_ints<std::uint32_t>(at, count, "SPECS (types)");
    specs_.resize(count);
    for (std::uint64_t i = 0; i < count; ++i) {
      if (paths[i] >= paths_.size() || paths_[paths[i]].parent == -2)
        fail("spec " + std::to_string(i) + " names path " + std::to_string(paths[i]) + ", which the PATHS section does not define");
      if (sets[i] >= fieldsets_.size()) fail("spec " + std::to_string(i) + " names field set " + std::to_string(sets[i]));
      specs_[i] = {paths[i], sets[i], types[i]};
    }
  }

  // --- values ----------------------------------------------------------------------------------

  /// Numbers of `n` elements of the layout at `offset` (raw, uncompressed).
  void raw_numbers(std::uint64_t offset, std::uint64_t n, Layout l, bool quat, Value& out) const {
    const int b = scalar_bytes(l.scalar);
    // The element count first (in doubles: n * components must not wrap around).
    check_count(n, offset, static_cast<double>(b) * l.components, "an array");
    const std::uint64_t total = n * static_cast<std::uint64_t>(l.components);
    need(offset, total * static_cast<std::uint64_t>(b), "an array");
    out.kind = Value::Kind::Numbers;
    out.width = l.components;
    const std::size_t base = out.numbers.size();
    out.numbers.resize(base + total);
    const char* p = bytes_.data() + offset;
    for (std::uint64_t i = 0; i < total; ++i, p += b) {
      double v = 0;
      switch (l.scalar) {
        case 0: { std::int32_t x; std::memcpy(&x, p, 4); v = x; break; }
        case 1: { std::uint32_t x; std::memcpy(&x, p, 4); v = x; break; }
        case 2: { float x; std::memcpy(&x, p, 4); v = x; break; }
        case 3: { double x; std::memcpy(&x, p, 8); v = x; break; }
        case 4: { std::uint16_t x; std::memcpy(&x, p, 2); v = half_to_double(x); break; }
        case 5: { std::int64_t x; std::memcpy(&x, p, 8); v = static_cast<double>(x); break; }
        case 6: { std::uint64_t x; std::memcpy(&x, p, 8); v = static_cast<double>(x); break; }
        default: v = static_cast<unsigned char>(*p); break;
      }
      out.numbers[base + i] = v;
    }
    if (quat)  // stored imaginary (x, y, z) then real; the text and our model put the real first
      for (std::uint64_t e = 0; e < n; ++e) std::rotate(out.numbers.begin() + static_cast<std::ptrdiff_t>(base + 4 * e),
                                                      out.numbers.begin() + static_cast<std::ptrdiff_t>(base + 4 * e + 3),
                                                      out.numbers.begin() + static_cast<std::ptrdiff_t>(base + 4 * e + 4));
  }

  std::vector<std::string> index_strings(std::uint64_t& at, int type, const char* what) const {
    const std::uint64_t n = get<std::uint64_t>(at, what);
    check_count(n, at, 4, what);
    std::vector<std::string> out;
    out.reserve(n);
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::uint32_t x = get<std::uint32_t>(at, what);
      out.push_back(type == kString || type == kStringVector || type == kStringListOp ? string_at(x, what)
                    : type == kPathVector || type == kPathListOp                          ? path_text(x)
                                                                                          : token(x, what));
    }
    return out;
  }

  std::string path_text(std::uint64_t p) const {
    if (p >= paths_.size() || paths_[p].parent == -2) fail("a value names path " + std::to_string(p) + ", which is not defined");
    std::vector<const PathNode*> chain;
    for (std::int64_t q = static_cast<std::int64_t>(p); q >= 0; q = paths_[static_cast<std::size_t>(q)].parent)
      chain.push_back(&paths_[static_cast<std::size_t>(q)]);
    std::string s;
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      if (!(*it)->element) continue;
      const std::string& e = *(*it)->element;
      s += (*it)->property ? "." + e : (e.front() == '{' ? e : "/" + e);
    }
    return s.empty() ? "/" : s;
  }

  Value value(std::uint64_t rep, const char* what) const {
    Value out;
    const int type = static_cast<int>((rep >> 48) & 0xff);
    const std::uint64_t payload = rep & kPayloadMask;
    const Layout l = layout(type);
    if (rep & kArrayBit) {
      out.array = true;
      if (payload == 0) {
        out.kind = l.components ? Value::Kind::Numbers : Value::Kind::Strings;
        out.width = std::max(l.components, 1);
        return out;
      }
      std::uint64_t at = payload;
      const std::uint64_t n = minor_ < 7 ? get<std::uint32_t>(at, what) : get<std::uint64_t>(at, what);
      if (type == kToken || type == kString || type == kAssetPath) {
        check_count(n, at, 4, what);
        out.kind = Value::Kind::Strings;
        for (std::uint64_t i = 0; i < n; ++i) {
          const std::uint32_t x = get<std::uint32_t>(at, what);
          out.strings.push_back(type == kString || type == kAssetPath ? string_at(x, what) : token(x, what));
        }
        return out;
      }
      if (!l.components) fail(std::string(what) + ": an array of unsupported type " + std::to_string(type));
      const bool compressed = (rep & kCompressedBit) && n >= kMinCompressedArray && l.components == 1;
      if (compressed && (type == kInt || type == kUInt || type == kInt64 || type == kUInt64)) {
        out.kind = Value::Kind::Numbers;
        if (type == kInt || type == kUInt) {
          const auto ints = compressed_ints<std::uint32_t>(at, n, what);
          for (std::uint32_t x : ints) out.numbers.push_back(type == kInt ? static_cast<double>(static_cast<std::int32_t>(x)) : x);
        } else {
          const auto ints = compressed_ints<std::uint64_t>(at, n, what);
          for (std::uint64_t x : ints) out.numbers.push_back(type == kInt64 ? static_cast<double>(static_cast<std::int64_t>(x)) : static_cast<double>(x));
        }
        return out;
      }
      if (compressed && (type == kFloat || type == kDouble || type == kHalf)) {
        out.kind = Value::Kind::Numbers;
        const char code = get<char>(at, what);
        if (code == 'i') {
          const auto ints = compressed_ints<std::uint32_t>(at, n, what);
          for (std::uint32_t x : ints) out.numbers.push_back(static_cast<std::int32_t>(x));
        } else if (code == 't') {
          const std::uint32_t lut_size = get<std::uint32_t>(at, what);
          Value lut;
          raw_numbers(at, lut_size, l, false, lut);
          at += static_cast<std::uint64_t>(lut_size) * static_cast<std::uint64_t>(scalar_bytes(l.scalar));
          const auto indexes = compressed_ints<std::uint32_t>(at, n, what);
          for (std::uint32_t x : indexes) {
            if (x >= lut.numbers.size()) fail(std::string(what) + ": lookup index " + std::to_string(x) + " of " + std::to_string(lut.numbers.size()));
            out.numbers.push_back(lut.numbers[x]);
          }
        } else {
          fail(std::string(what) + ": unknown float array code");
        }
        return out;
      }
      raw_numbers(at, n, l, is_quat(type), out);
      return out;
    }
    const std::uint32_t low = static_cast<std::uint32_t>(payload & 0xffffffffu);
    switch (type) {
      case kToken: out.kind = Value::Kind::Strings; out.strings.push_back(token(low, what)); return out;
      case kString: case kAssetPath:
        out.kind = Value::Kind::Strings;
        out.strings.push_back(type == kString ? string_at(low, what) : token(low, what));
        return out;
      case kSpecifier: case kVariability: case kPermission: case kBool: case kUChar:
        out.kind = Value::Kind::Numbers; out.numbers.push_back(low); return out;
      case kValueBlock: return out;
      case kTokenVector: case kStringVector: case kPathVector: {
        std::uint64_t at = payload;
        out.kind = Value::Kind::Strings;
        out.array = true;
        out.strings = index_strings(at, type, what);
        return out;
      }
      case kDoubleVector: {
        std::uint64_t at = payload;
        const std::uint64_t n = get<std::uint64_t>(at, what);
        raw_numbers(at, n, {3, 1}, false, out);
        out.array = true;
        return out;
      }
      default: break;
    }
    if (!l.components) return out;  // a dictionary, list op or other value a cage does not need
    if ((rep & kInlinedBit) || type == kInt || type == kUInt || type == kFloat || type == kHalf) {
      out.kind = Value::Kind::Numbers;
      out.width = l.components;
      if (l.components == 1) {
        if (l.scalar == 2 || l.scalar == 3) { float f; std::memcpy(&f, &low, 4); out.numbers.push_back(f); }
        else if (l.scalar == 4) out.numbers.push_back(half_to_double(static_cast<std::uint16_t>(low)));
        else if (l.scalar == 1 || l.scalar == 6) out.numbers.push_back(low);
        else out.numbers.push_back(static_cast<std::int32_t>(low));
      } else if (type == kMatrix2d || type == kMatrix3d || type == kMatrix4d) {
        const int d = type == kMatrix2d ? 2 : type == kMatrix3d ? 3 : 4;
        out.numbers.assign(static_cast<std::size_t>(d * d), 0.0);
        for (int i = 0; i < d; ++i) out.numbers[static_cast<std::size_t>(i * d + i)] = static_cast<std::int8_t>((low >> (8 * i)) & 0xff);
      } else {
        for (int i = 0; i < l.components; ++i) out.numbers.push_back(static_cast<std::int8_t>((low >> (8 * i)) & 0xff));
      }
      return out;
    }
    raw_numbers(payload, 1, l, is_quat(type), out);
    return out;
  }

  /// The list op's items that add to the list (explicit, added, prepended, appended) as strings.
  std::vector<std::string> list_op_strings(std::uint64_t rep, const char* what) const {
    const int type = static_cast<int>((rep >> 48) & 0xff);
    std::vector<std::string> out;
    if (rep & kInlinedBit) return out;
    std::uint64_t at = rep & kPayloadMask;
    const std::uint8_t header = get<std::uint8_t>(at, what);
    for (int bit = 1; bit <= 6; ++bit) {
      if (!(header & (1u << bit))) continue;
      std::vector<std::string> items = index_strings(at, type, what);
      if (bit != 3) out.insert(out.end(), items.begin(), items.end());  // bit 3: deleted items
    }
    return out;
  }

  /// Skips a dictionary (uint64 count, then per entry a string index and a relative jump to the
  /// value rep), as inside a reference's custom data.
  void skip_dictionary(std::uint64_t& at, const char* what) const {
    const std::uint64_t n = get<std::uint64_t>(at, what);
    check_count(n, at, 12, what);
    for (std::uint64_t i = 0; i < n; ++i) {
      get<std::uint32_t>(at, what);
      const std::uint64_t start = at;
      const std::int64_t jump = get<std::int64_t>(at, what);
      const std::int64_t target = static_cast<std::int64_t>(start) + jump;
      if (jump <= 0 || target < 0 || static_cast<std::uint64_t>(target) + 8 > bytes_.size())
        fail(std::string(what) + ": a dictionary value is outside the file");
      at = static_cast<std::uint64_t>(target) + 8;
    }
  }

  /// References (ReferenceListOp) or payloads: (asset, prim path) pairs that add.
  std::vector<std::pair<std::string, std::string>> references(std::uint64_t rep, const char* what) const {
    const int type = static_cast<int>((rep >> 48) & 0xff);
    std::vector<std::pair<std::string, std::string>> out;
    std::uint64_t at = rep & kPayloadMask;
    auto one = [&](std::uint64_t& p, bool reference) {
      std::string asset = string_at(get<std::uint32_t>(p, what), what);
      std::string path;
      const std::uint32_t pi = get<std::uint32_t>(p, what);
      if (pi < paths_.size() && paths_[pi].parent != -2) path = path_text(pi);
      if (reference || minor_ >= 8) { get<double>(p, what); get<double>(p, what); }
      if (reference) skip_dictionary(p, what);
      return std::make_pair(asset, path == "/" ? std::string() : path);
    };
    if (type == kPayload) {
      out.push_back(one(at, false));
      return out;
    }
    if (type != kReferenceListOp && type != kPayloadListOp) return out;
    const std::uint8_t header = get<std::uint8_t>(at, what);
    for (int bit = 1; bit <= 6; ++bit) {
      if (!(header & (1u << bit))) continue;
      const std::uint64_t n = get<std::uint64_t>(at, what);
      check_count(n, at, 8, what);
      for (std::uint64_t i = 0; i < n; ++i) {
        auto r = one(at, type == kReferenceListOp);
        if (bit != 3) out.push_back(std::move(r));
      }
    }
    return out;
  }

  void time_samples(std::uint64_t rep, Attribute& a, const char* what) const {
    std::uint64_t at = rep & kPayloadMask;
    std::uint64_t start = at;
    std::int64_t jump = get<std::int64_t>(at, what);
    if (jump < 0 || start + static_cast<std::uint64_t>(jump) > bytes_.size()) fail(std::string(what) + ": time samples outside the file");
    at = start + static_cast<std::uint64_t>(jump);
    const std::uint64_t times_rep = get<std::uint64_t>(at, what);
    start = at;
    jump = get<std::int64_t>(at, what);
    if (jump < 0 || start + static_cast<std::uint64_t>(jump) > bytes_.size()) fail(std::string(what) + ": time samples outside the file");
    at = start + static_cast<std::uint64_t>(jump);
    const std::uint64_t n = get<std::uint64_t>(at, what);
    check_count(n, at, 8, what);
    const Value times = value(times_rep, what);
    if (times.numbers.size() != n) fail(std::string(what) + ": " + std::to_string(times.numbers.size()) + " times for " + std::to_string(n) + " samples");
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::uint64_t r = get<std::uint64_t>(at, what);
      if (((r >> 48) & 0xff) == kTimeSamples) fail(std::string(what) + ": time samples inside time samples");
      a.samples.emplace_back(times.numbers[i], value(r, what));
    }
  }

  // --- the layer -------------------------------------------------------------------------------

  /// The prim (or variant) spec a path names, created on the way.
  PrimSpec& prim_at(std::uint32_t p) {
    if (paths_[p].parent == -1) return layer_.root;
    std::vector<std::uint32_t> chain;
    for (std::int64_t q = p; paths_[static_cast<std::size_t>(q)].parent >= 0; q = paths_[static_cast<std::size_t>(q)].parent)
      chain.push_back(static_cast<std::uint32_t>(q));
    PrimSpec* spec = &layer_.root;
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      const PathNode& node = paths_[*it];
      const std::string& e = *node.element;
      if (node.property) fail("path " + path_text(p) + " nests under a property");
      if (!e.empty() && e.front() == '{') {
        const std::size_t eq = e.find('=');
        if (eq == std::string::npos || e.back() != '}') fail("malformed variant selection in path " + path_text(p));
        const std::string set = e.substr(1, eq - 1), variant = e.substr(eq + 1, e.size() - eq - 2);
        VariantSet& vs = spec->variant_set_or_add(set);
        if (variant.empty()) return *spec;  // the variant set's own spec
        PrimSpec* found = nullptr;
        for (auto& [n, s] : vs.variants)
          if (n == variant) found = s.get();
        if (!found) {
          vs.variants.emplace_back(variant, std::make_unique<PrimSpec>());
          found = vs.variants.back().second.get();
          found->name = variant;
        }
        spec = found;
      } else {
        spec = &spec->child_or_add(e);
      }
    }
    return *spec;
  }

  void build_layer() {
    if (static_cast<long>(specs_.size()) > limits_.max_prims) fail("more than " + std::to_string(limits_.max_prims) + " specs");
    for (const Spec& s : specs_) {
      std::vector<const Field*> fs;
      for (std::size_t f = s.fieldset; f < fieldsets_.size() && fieldsets_[f] != ~0u; ++f) {
        fs.push_back(&fields_[fieldsets_[f]]);
        if (fs.size() > 10000) fail("a field set has more than 10000 fields");
      }
      if (s.type == kAttributeSpec) {
        const PathNode& node = paths_[s.path];
        if (!node.property || node.parent < 0) fail("attribute spec at " + path_text(s.path) + " is not a property path");
        PrimSpec& prim = prim_at(static_cast<std::uint32_t>(node.parent));
        Attribute& a = prim.attribute_or_add(*node.element);
        for (const Field* f : fs) {
          const std::string& n = *f->name;
          if (n == "typeName") {
            const Value v = value(f->rep, "typeName");
            if (!v.strings.empty()) a.type_name = v.strings[0];
          } else if (n == "default") {
            a.default_value = value(f->rep, node.element->c_str());
            a.has_default = true;
          } else if (n == "timeSamples") {
            time_samples(f->rep, a, node.element->c_str());
          }
        }
      } else if (s.type == kPrimSpec || s.type == kVariantSpec || s.type == kPseudoRootSpec) {
        PrimSpec& prim = prim_at(s.path);
        if (prim.line == 0 && s.type == kPrimSpec) prim.line = -1;
        for (const Field* f : fs) {
          const std::string& n = *f->name;
          const int type = static_cast<int>((f->rep >> 48) & 0xff);
          if (n == "specifier") {
            const Value v = value(f->rep, "specifier");
            const double x = v.numbers.empty() ? 1 : v.numbers[0];
            prim.specifier = x == 0 ? Specifier::Def : x == 2 ? Specifier::Class : Specifier::Over;
          } else if (n == "typeName") {
            const Value v = value(f->rep, "typeName");
            if (!v.strings.empty()) prim.type_name = v.strings[0];
          } else if (n == "primChildren" && type == kTokenVector) {
            for (const std::string& c : value(f->rep, "primChildren").strings) prim.child_or_add(c);
          } else if (n == "variantSetNames" && type == kStringListOp) {
            for (const std::string& c : list_op_strings(f->rep, "variantSetNames")) prim.variant_set_or_add(c);
          } else if (n == "variantSelection" && type == kVariantSelectionMap) {
            std::uint64_t at = f->rep & kPayloadMask;
            const std::uint64_t count = get<std::uint64_t>(at, "variantSelection");
            check_count(count, at, 8, "variantSelection");
            for (std::uint64_t i = 0; i < count; ++i) {
              const std::string& set = string_at(get<std::uint32_t>(at, "variantSelection"), "variantSelection");
              prim.variant_selection[set] = string_at(get<std::uint32_t>(at, "variantSelection"), "variantSelection");
            }
          } else if (n == "references" || n == "payload") {
            for (const auto& [asset, path] : references(f->rep, n.c_str())) {
              if (asset.empty() && !path.empty()) prim.internal_references.push_back(path);
              else prim.external_references.push_back(n + " @" + asset + "@");
            }
          } else if (n == "inherits" || n == "specializes") {
            for (const std::string& path : list_op_strings(f->rep, n.c_str())) prim.external_references.push_back(n + " <" + path + ">");
          } else if (n == "instanceable") {
            const Value v = value(f->rep, "instanceable");
            prim.instanceable = !v.numbers.empty() && v.numbers[0] != 0;
          } else if (n == "active") {
            const Value v = value(f->rep, "active");
            if (!v.numbers.empty()) prim.active = v.numbers[0] != 0 ? 1 : 0;
          } else if (s.type == kPseudoRootSpec) {
            if (n == "metersPerUnit") {
              const Value v = value(f->rep, "metersPerUnit");
              if (!v.numbers.empty()) layer_.meters_per_unit = v.numbers[0];
            } else if (n == "upAxis" || n == "defaultPrim") {
              const Value v = value(f->rep, n.c_str());
              if (!v.strings.empty()) (n == "upAxis" ? layer_.up_axis : layer_.default_prim) = v.strings[0];
            } else if (n == "subLayers") {
              layer_.notes.push_back("the sublayers of the file are not read");
            }
          }
        }
      }
    }
  }

  struct Field {
    const std::string* name = nullptr;
    std::uint64_t rep = 0;
  };

  std::string_view bytes_;
  const std::string& name_;
  const Limits& limits_;
  Layer& layer_;
  int major_ = 0, minor_ = 0, patch_ = 0;
  std::uint64_t toc_ = 0;
  std::vector<std::string> tokens_;
  std::vector<std::uint32_t> strings_;
  std::vector<Field> fields_;
  std::vector<std::uint32_t> fieldsets_;
  std::vector<PathNode> paths_;
  std::vector<Spec> specs_;
};

}  // namespace

void parse_usdc(std::string_view bytes, const std::string& name, const Limits& limits, Layer& layer) {
  Crate(bytes, name, limits, layer).parse();
}

}  // namespace subd2nurbs::usd
