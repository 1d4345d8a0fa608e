// A tiny writer of USD crate (usdc 0.8.0) files for the tests, written from the format's
// description (OpenUSD crateFile.cpp), independent of io/usd_crate.cpp: the structural sections
// compressed as the format requires (integer coding + LZ4), values uncompressed except int
// arrays of 16 or more entries when asked (the compressed-array path).
#pragma once

#include <lz4.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace subd2nurbs::testing {

class CrateWriter {
 public:
  enum Type : int { kInt = 3, kFloat = 8, kDouble = 9, kToken = 11, kVec3f = 24, kVec3d = 23, kQuatf = 17,
                    kMatrix4d = 15, kTokenVector = 41, kSpecifier = 42, kVariability = 44 };
  enum SpecType : std::uint32_t { kAttribute = 1, kPrim = 6, kPseudoRoot = 7 };

  CrateWriter() {
    data_.assign(88, '\0');
    token("");  // token 0
    paths_.push_back({-1, "", false, {}});  // the root
  }

  std::uint32_t token(const std::string& t) {
    auto it = token_index_.find(t);
    if (it != token_index_.end()) return it->second;
    tokens_.push_back(t);
    return token_index_[t] = static_cast<std::uint32_t>(tokens_.size() - 1);
  }

  static std::uint64_t rep(int type, std::uint64_t payload, bool inlined, bool array = false, bool compressed = false) {
    return (array ? 1ull << 63 : 0) | (inlined ? 1ull << 62 : 0) | (compressed ? 1ull << 61 : 0) |
           (static_cast<std::uint64_t>(type) << 48) | (payload & ((1ull << 48) - 1));
  }

  std::uint64_t token_value(const std::string& t) { return rep(kToken, token(t), true); }
  std::uint64_t specifier(int s) { return rep(kSpecifier, static_cast<std::uint64_t>(s), true); }
  std::uint64_t double_value(double d) {  // not inlined: 8 bytes in the file
    const std::uint64_t at = align();
    put(d);
    return rep(kDouble, at, false);
  }
  std::uint64_t token_vector(const std::vector<std::string>& ts) {
    const std::uint64_t at = align();
    put<std::uint64_t>(ts.size());
    for (const auto& t : ts) put<std::uint32_t>(token(t));
    return rep(kTokenVector, at, false);
  }
  std::uint64_t token_array(const std::vector<std::string>& ts) {
    const std::uint64_t at = align();
    put<std::uint64_t>(ts.size());
    for (const auto& t : ts) put<std::uint32_t>(token(t));
    return rep(kToken, at, false, true);
  }
  std::uint64_t int_array(const std::vector<int>& v, bool compress) {
    const std::uint64_t at = align();
    put<std::uint64_t>(v.size());
    const bool c = compress && v.size() >= 16;
    if (c) {
      const std::string packed = compress_ints(std::vector<std::int32_t>(v.begin(), v.end()));
      put<std::uint64_t>(packed.size());
      data_ += packed;
    } else {
      for (int x : v) put<std::int32_t>(x);
    }
    return rep(kInt, at, false, true, c);
  }
  std::uint64_t float_array(const std::vector<float>& v) {
    const std::uint64_t at = align();
    put<std::uint64_t>(v.size());
    for (float x : v) put(x);
    return rep(kFloat, at, false, true);
  }
  std::uint64_t vec3f_array(const std::vector<std::array<float, 3>>& v) {
    const std::uint64_t at = align();
    put<std::uint64_t>(v.size());
    for (const auto& p : v)
      for (float x : p) put(x);
    return rep(kVec3f, at, false, true);
  }
  std::uint64_t vec3d(const std::array<double, 3>& v) {
    const std::uint64_t at = align();
    for (double x : v) put(x);
    return rep(kVec3d, at, false);
  }

  /// A path element under `parent` (0: the root); returns the path's index.
  int path(int parent, const std::string& element, bool property = false) {
    token(element);
    paths_.push_back({parent, element, property, {}});
    const int index = static_cast<int>(paths_.size() - 1);
    paths_[static_cast<std::size_t>(parent)].children.push_back(index);
    return index;
  }

  void spec(int path_index, SpecType type, const std::vector<std::pair<std::string, std::uint64_t>>& fields) {
    const std::uint32_t set = static_cast<std::uint32_t>(fieldsets_.size());
    for (const auto& [name, value] : fields) {
      fields_.push_back({token(name), value});
      fieldsets_.push_back(static_cast<std::uint32_t>(fields_.size() - 1));
    }
    fieldsets_.push_back(~0u);
    specs_.push_back({static_cast<std::uint32_t>(path_index), set, type});
  }

  /// The file's bytes.
  std::string finish() {
    struct Section {
      const char* name;
      std::uint64_t start, size;
    };
    std::vector<Section> sections;
    auto begin = [&](const char* name) { sections.push_back({name, align(), 0}); };
    auto end = [&]() { sections.back().size = data_.size() - sections.back().start; };

    begin("TOKENS");
    std::string chars;
    for (const auto& t : tokens_) chars += t + std::string(1, '\0');
    const std::string packed = fast_compress(chars);
    put<std::uint64_t>(tokens_.size());
    put<std::uint64_t>(chars.size());
    put<std::uint64_t>(packed.size());
    data_ += packed;
    end();

    begin("STRINGS");
    put<std::uint64_t>(0);
    end();

    begin("FIELDS");
    put<std::uint64_t>(fields_.size());
    std::vector<std::int32_t> names;
    std::string reps;
    for (const auto& f : fields_) {
      names.push_back(static_cast<std::int32_t>(f.first));
      reps.append(reinterpret_cast<const char*>(&f.second), 8);
    }
    put_ints(names);
    const std::string packed_reps = fast_compress(reps);
    put<std::uint64_t>(packed_reps.size());
    data_ += packed_reps;
    end();

    begin("FIELDSETS");
    put<std::uint64_t>(fieldsets_.size());
    put_ints(std::vector<std::int32_t>(fieldsets_.begin(), fieldsets_.end()));
    end();

    begin("PATHS");
    std::vector<std::int32_t> index, element, jump;
    encode_path(0, false, index, element, jump);
    put<std::uint64_t>(paths_.size());
    put<std::uint64_t>(index.size());
    put_ints(index);
    put_ints(element);
    put_ints(jump);
    end();

    begin("SPECS");
    put<std::uint64_t>(specs_.size());
    std::vector<std::int32_t> p, s, t;
    for (const auto& sp : specs_) {
      p.push_back(static_cast<std::int32_t>(sp.path));
      s.push_back(static_cast<std::int32_t>(sp.set));
      t.push_back(static_cast<std::int32_t>(sp.type));
    }
    put_ints(p);
    put_ints(s);
    put_ints(t);
    end();

    const std::uint64_t toc = align();
    put<std::uint64_t>(sections.size());
    for (const auto& sec : sections) {
      char name[16] = {};
      std::strncpy(name, sec.name, 15);
      data_.append(name, 16);
      put(sec.start);
      put(sec.size);
    }
    std::memcpy(data_.data(), "PXR-USDC", 8);
    data_[8] = 0, data_[9] = 8, data_[10] = 0;
    std::memcpy(data_.data() + 16, &toc, 8);
    return data_;
  }

  /// Integer coding (deltas, the most common delta, 2-bit codes, 8/16/32-bit values) + LZ4.
  static std::string compress_ints(const std::vector<std::int32_t>& v) {
    std::map<std::int32_t, int> count;
    std::int32_t prev = 0;
    for (std::int32_t x : v) ++count[x - prev], prev = x;
    std::int32_t common = 0;
    int best = 0;
    for (const auto& [d, n] : count)
      if (n >= best) best = n, common = d;
    std::string out(reinterpret_cast<const char*>(&common), 4);
    std::string codes((v.size() * 2 + 7) / 8, '\0'), values;
    prev = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
      const std::int32_t d = v[i] - prev;
      prev = v[i];
      int code = 0;
      if (d == common) code = 0;
      else if (d >= -128 && d <= 127) code = 1, values += static_cast<char>(static_cast<std::int8_t>(d));
      else if (d >= -32768 && d <= 32767) {
        code = 2;
        const std::int16_t s = static_cast<std::int16_t>(d);
        values.append(reinterpret_cast<const char*>(&s), 2);
      } else {
        code = 3;
        values.append(reinterpret_cast<const char*>(&d), 4);
      }
      codes[i / 4] = static_cast<char>(codes[i / 4] | (code << (2 * (i % 4))));
    }
    return fast_compress(out + codes + values);
  }

  static std::string fast_compress(const std::string& raw) {
    std::string out(static_cast<std::size_t>(LZ4_compressBound(static_cast<int>(raw.size()))) + 1, '\0');
    const int n = LZ4_compress_default(raw.data(), out.data() + 1, static_cast<int>(raw.size()),
                                       static_cast<int>(out.size() - 1));
    out.resize(static_cast<std::size_t>(n) + 1);
    return out;
  }

  std::string& bytes() { return data_; }

 private:
  struct PathNode {
    int parent;
    std::string element;
    bool property;
    std::vector<int> children;
  };
  struct Spec {
    std::uint32_t path, set, type;
  };

  template <class T>
  void put(T x) {
    data_.append(reinterpret_cast<const char*>(&x), sizeof x);
  }
  std::uint64_t align() {
    while (data_.size() % 8) data_ += '\0';
    return data_.size();
  }
  void put_ints(const std::vector<std::int32_t>& v) {
    const std::string packed = compress_ints(v);
    put<std::uint64_t>(packed.size());
    data_ += packed;
  }
  void encode_path(int node, bool sibling, std::vector<std::int32_t>& index, std::vector<std::int32_t>& element,
                   std::vector<std::int32_t>& jump) {
    const std::size_t at = index.size();
    const PathNode& n = paths_[static_cast<std::size_t>(node)];
    index.push_back(node);
    const std::int32_t tok = static_cast<std::int32_t>(token(n.element));
    element.push_back(n.property ? -tok : tok);
    jump.push_back(0);
    for (std::size_t k = 0; k < n.children.size(); ++k)
      encode_path(n.children[k], k + 1 < n.children.size(), index, element, jump);
    const bool child = !n.children.empty();
    jump[at] = child && sibling ? static_cast<std::int32_t>(index.size() - at) : child ? -1 : sibling ? 0 : -2;
  }

  std::string data_;
  std::vector<std::string> tokens_;
  std::map<std::string, std::uint32_t> token_index_;
  std::vector<std::pair<std::uint32_t, std::uint64_t>> fields_;
  std::vector<std::uint32_t> fieldsets_;
  std::vector<PathNode> paths_;
  std::vector<Spec> specs_;
};

}  // namespace subd2nurbs::testing
