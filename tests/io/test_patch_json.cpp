// patch_set_to_json / write_patch_json: the text parses back (with a minimal strict JSON
// parser written here) to exactly the values of the PatchSet, in the documented layout.
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/input_error.h"
#include "io/patch_json.h"
#include "io/sample_patch_set.h"
#include "io/temp_dir.h"

using namespace subd2nurbs;
using subd2nurbs::testing::read_text;
using subd2nurbs::testing::sample_patch_set;
using subd2nurbs::testing::TempDir;

namespace {

// --- a minimal strict JSON parser (RFC 8259 grammar; strings without escapes suffice) ------

struct Json {
  enum Type { Null, Bool, Number, String, Array, Object } type = Null;
  bool b = false;
  double num = 0;
  std::string str;                                  // String; also the number's text
  std::vector<Json> items;                          // Array
  std::vector<std::pair<std::string, Json>> keys;   // Object, in file order

  const Json& operator[](const std::string& k) const {
    for (const auto& [name, value] : keys)
      if (name == k) return value;
    throw std::out_of_range("no key " + k);
  }
  const Json& operator[](size_t i) const { return items.at(i); }
  bool has(const std::string& k) const {
    for (const auto& kv : keys)
      if (kv.first == k) return true;
    return false;
  }
  std::vector<std::string> key_names() const {
    std::vector<std::string> out;
    for (const auto& kv : keys) out.push_back(kv.first);
    return out;
  }
};

class Parser {
 public:
  explicit Parser(const std::string& text) : s_(text) {}
  Json parse() {
    Json v = value();
    ws();
    if (i_ != s_.size()) fail("trailing characters");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error("JSON: " + what + " at offset " + std::to_string(i_));
  }
  void ws() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\n' || s_[i_] == '\r' || s_[i_] == '\t')) ++i_;
  }
  void expect(char c) {
    ws();
    if (i_ >= s_.size() || s_[i_] != c) fail(std::string("expected '") + c + "'");
    ++i_;
  }
  bool literal(const char* w) {
    const size_t n = std::strlen(w);
    if (s_.compare(i_, n, w) != 0) return false;
    i_ += n;
    return true;
  }
  std::string string() {
    expect('"');
    std::string out;
    while (i_ < s_.size() && s_[i_] != '"') {
      if (s_[i_] == '\\' || static_cast<unsigned char>(s_[i_]) < 0x20) fail("escape or control character");
      out += s_[i_++];
    }
    if (i_ >= s_.size()) fail("unterminated string");
    ++i_;
    return out;
  }
  Json number() {
    // -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?
    const size_t start = i_;
    auto digits = [&] {
      const size_t d = i_;
      while (i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]))) ++i_;
      if (i_ == d) fail("digit expected");
    };
    if (s_[i_] == '-') ++i_;
    if (i_ < s_.size() && s_[i_] == '0') ++i_;
    else digits();
    if (i_ < s_.size() && s_[i_] == '.') { ++i_; digits(); }
    if (i_ < s_.size() && (s_[i_] == 'e' || s_[i_] == 'E')) {
      ++i_;
      if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) ++i_;
      digits();
    }
    Json j;
    j.type = Json::Number;
    j.str = s_.substr(start, i_ - start);
    j.num = std::strtod(j.str.c_str(), nullptr);
    return j;
  }
  Json value() {
    ws();
    if (i_ >= s_.size()) fail("value expected");
    Json j;
    const char c = s_[i_];
    if (c == '{') {
      j.type = Json::Object;
      ++i_;
      ws();
      if (s_[i_] == '}') { ++i_; return j; }
      for (;;) {
        std::string k = string();
        expect(':');
        j.keys.emplace_back(k, value());
        ws();
        if (s_[i_] == ',') { ++i_; continue; }
        expect('}');
        return j;
      }
    }
    if (c == '[') {
      j.type = Json::Array;
      ++i_;
      ws();
      if (s_[i_] == ']') { ++i_; return j; }
      for (;;) {
        j.items.push_back(value());
        ws();
        if (s_[i_] == ',') { ++i_; continue; }
        expect(']');
        return j;
      }
    }
    if (c == '"') {
      j.type = Json::String;
      j.str = string();
      return j;
    }
    if (literal("true")) { j.type = Json::Bool; j.b = true; return j; }
    if (literal("false")) { j.type = Json::Bool; return j; }
    if (literal("null")) return j;
    if (c == '-' || std::isdigit(static_cast<unsigned char>(c))) return number();
    fail("unexpected character");
  }

  const std::string& s_;
  size_t i_ = 0;
};

Json parse(const std::string& text) { return Parser(text).parse(); }

// --- exact comparisons -------------------------------------------------------------------

bool same_double(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }  // -0 != 0

void expect_number(const Json& j, double x, const std::string& where) {
  ASSERT_EQ(j.type, Json::Number) << where;
  EXPECT_TRUE(same_double(j.num, x)) << where << ": " << j.str << " vs " << x;
}
void expect_int(const Json& j, int x, const std::string& where) {
  ASSERT_EQ(j.type, Json::Number) << where;
  EXPECT_EQ(j.str, std::to_string(x)) << where;
}
void expect_bool(const Json& j, bool x, const std::string& where) {
  ASSERT_EQ(j.type, Json::Bool) << where;
  EXPECT_EQ(j.b, x) << where;
}
template <class T>
void expect_ints(const Json& j, const T& xs, const std::string& where) {
  ASSERT_EQ(j.type, Json::Array) << where;
  ASSERT_EQ(j.items.size(), xs.size()) << where;
  for (size_t i = 0; i < xs.size(); ++i) expect_int(j[i], xs[i], where + "[" + std::to_string(i) + "]");
}
template <class Points>
void expect_points(const Json& j, const Points& ps, const std::string& where) {
  ASSERT_EQ(j.type, Json::Array) << where;
  ASSERT_EQ(j.items.size(), ps.size()) << where;
  for (size_t i = 0; i < ps.size(); ++i) {
    ASSERT_EQ(j[i].items.size(), 3u) << where;
    for (int k = 0; k < 3; ++k) expect_number(j[i][k], ps[i][k], where + "[" + std::to_string(i) + "]");
  }
}
void expect_knots(const Json& j, const KnotVector& kv, const std::string& where) {
  EXPECT_EQ(j.key_names(), (std::vector<std::string>{"values", "mults", "periodic"})) << where;
  ASSERT_EQ(j["values"].items.size(), kv.knots.size()) << where;
  for (size_t i = 0; i < kv.knots.size(); ++i) expect_number(j["values"][i], kv.knots[i], where);
  expect_ints(j["mults"], kv.mults, where + ".mults");
  expect_bool(j["periodic"], kv.periodic, where + ".periodic");
}

/// Every value of `ps` is in `j`, exactly, in the documented layout and key order.
void expect_round_trip(const PatchSet& ps, const Json& j) {
  EXPECT_EQ(j.key_names(), (std::vector<std::string>{"format", "version", "model_size", "closed",
                                                      "patches", "curves", "corners"}));
  EXPECT_EQ(j["format"].str, "subd2nurbs-patches");
  expect_int(j["version"], 1, "version");
  expect_number(j["model_size"], ps.model_size, "model_size");
  expect_bool(j["closed"], ps.closed, "closed");

  ASSERT_EQ(j["patches"].items.size(), ps.patches.size());
  for (size_t p = 0; p < ps.patches.size(); ++p) {
    const NurbsPatch& np = ps.patches[p];
    const Json& jp = j["patches"][p];
    const std::string w = "patch " + std::to_string(p);
    std::vector<std::string> keys = {"kind", "degree", "knots_u", "knots_v", "num_poles", "poles"};
    if (!np.weights.empty()) keys.push_back("weights");
    for (const char* k : {"base_faces", "corners", "curves", "curve_reversed"}) keys.push_back(k);
    EXPECT_EQ(jp.key_names(), keys) << w;
    EXPECT_EQ(jp["kind"].str, to_string(np.kind)) << w;
    expect_ints(jp["degree"], std::vector<int>{np.degree_u, np.degree_v}, w + ".degree");
    expect_knots(jp["knots_u"], np.knots_u, w + ".knots_u");
    expect_knots(jp["knots_v"], np.knots_v, w + ".knots_v");
    expect_ints(jp["num_poles"], std::vector<int>{np.num_poles_u, np.num_poles_v}, w + ".num_poles");
    expect_points(jp["poles"], np.poles, w + ".poles");
    if (!np.weights.empty()) {
      ASSERT_EQ(jp["weights"].items.size(), np.weights.size()) << w;
      for (size_t i = 0; i < np.weights.size(); ++i) expect_number(jp["weights"][i], np.weights[i], w);
    }
    expect_ints(jp["base_faces"], np.base_faces, w + ".base_faces");
    expect_ints(jp["corners"], np.corners, w + ".corners");
    expect_ints(jp["curves"], np.curves, w + ".curves");
    ASSERT_EQ(jp["curve_reversed"].items.size(), 4u);
    for (int s = 0; s < 4; ++s) expect_bool(jp["curve_reversed"][s], np.curve_reversed[s], w);
  }

  ASSERT_EQ(j["curves"].items.size(), ps.curves.size());
  for (size_t c = 0; c < ps.curves.size(); ++c) {
    const BoundaryCurve& bc = ps.curves[c];
    const Json& jc = j["curves"][c];
    const std::string w = "curve " + std::to_string(c);
    EXPECT_EQ(jc.key_names(),
              (std::vector<std::string>{"corners", "degree", "knots", "poles", "continuity", "uses"}));
    expect_ints(jc["corners"], std::vector<int>{bc.corner0, bc.corner1}, w + ".corners");
    expect_int(jc["degree"], bc.degree, w + ".degree");
    expect_knots(jc["knots"], bc.knots, w + ".knots");
    expect_points(jc["poles"], bc.poles, w + ".poles");
    EXPECT_EQ(jc["continuity"].str, to_string(bc.continuity)) << w;
    ASSERT_EQ(jc["uses"].items.size(), bc.uses.size()) << w;
    for (size_t u = 0; u < bc.uses.size(); ++u) {
      const Json& ju = jc["uses"][u];
      EXPECT_EQ(ju.key_names(), (std::vector<std::string>{"patch", "side", "reversed"}));
      expect_int(ju["patch"], bc.uses[u].patch, w);
      expect_int(ju["side"], bc.uses[u].side, w);
      expect_bool(ju["reversed"], bc.uses[u].reversed, w);
    }
  }

  ASSERT_EQ(j["corners"].items.size(), ps.corners.size());
  for (size_t c = 0; c < ps.corners.size(); ++c) {
    const Json& jc = j["corners"][c];
    EXPECT_EQ(jc.key_names(), (std::vector<std::string>{"position", "base_vertex"}));
    expect_points(Json{Json::Array, false, 0, "", {jc["position"]}, {}}, std::vector<Point3>{ps.corners[c].position},
                  "corner " + std::to_string(c));
    expect_int(jc["base_vertex"], ps.corners[c].base_vertex, "corner " + std::to_string(c));
  }
}

}  // namespace

TEST(PatchJson, ParsesBackToTheExactValues) {
  const PatchSet ps = sample_patch_set();
  const std::string text = patch_set_to_json(ps);
  Json j;
  ASSERT_NO_THROW(j = parse(text)) << text;
  expect_round_trip(ps, j);
}

TEST(PatchJson, NumbersUseShortestExactFormAndKindNames) {
  const std::string text = patch_set_to_json(sample_patch_set());
  EXPECT_EQ(text.rfind("{\"format\":\"subd2nurbs-patches\",\"version\":1,\"model_size\":0.66666666666666663,"
                       "\"closed\":false,\n",
                       0),
            0u)
      << text.substr(0, 120);
  EXPECT_NE(text.find("{\"kind\":\"regular\",\"degree\":[3,3],\"knots_u\":{\"values\":[0,1],\"mults\":[4,4],"
                      "\"periodic\":false}"),
            std::string::npos);
  for (const char* s : {"\"kind\":\"pccm\"", "\"kind\":\"polar_cap\"", "\"continuity\":\"boundary\"",
                        "\"continuity\":\"G1\"", "[-0.0,", "4.9406564584124654e-324", "1e-300",
                        "1.2345678901234567e+300", "\"base_faces\":[]", "\"base_vertex\":-1}",
                        "\"uses\":[{\"patch\":0,\"side\":2,\"reversed\":true},{\"patch\":1,\"side\":0,"
                        "\"reversed\":true}]"})
    EXPECT_NE(text.find(s), std::string::npos) << s;
  // weights only on the rational patch
  size_t count = 0;
  for (size_t at = text.find("\"weights\""); at != std::string::npos; at = text.find("\"weights\"", at + 1))
    ++count;
  EXPECT_EQ(count, 1u);
  EXPECT_EQ(text.back(), '\n');
}

TEST(PatchJson, IsDeterministicAndOneElementPerLine) {
  const PatchSet ps = sample_patch_set();
  const std::string text = patch_set_to_json(ps);
  EXPECT_EQ(text, patch_set_to_json(ps));
  size_t lines = 0;
  for (char c : text) lines += c == '\n';
  // The header line, then per list: its opening line, one line per element, its closing line.
  EXPECT_EQ(lines, 1 + (ps.patches.size() + 2) + (ps.curves.size() + 2) + (ps.corners.size() + 2));
  EXPECT_NE(text.find("\n\"patches\":[\n{\"kind\""), std::string::npos);
  EXPECT_NE(text.find("\n],\n\"curves\":[\n{\"corners\""), std::string::npos);
}

TEST(PatchJson, EmptySetIsValidJson) {
  PatchSet empty;
  empty.closed = true;
  const std::string text = patch_set_to_json(empty);
  Json j;
  ASSERT_NO_THROW(j = parse(text)) << text;
  expect_round_trip(empty, j);
  EXPECT_EQ(text,
            "{\"format\":\"subd2nurbs-patches\",\"version\":1,\"model_size\":1,\"closed\":true,\n"
            "\"patches\":[],\n\"curves\":[],\n\"corners\":[]}\n");
}

TEST(PatchJson, NonFiniteValuesAreRejected) {
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                     -std::numeric_limits<double>::infinity()}) {
    PatchSet ps = sample_patch_set();
    ps.patches[1].weights[3] = bad;
    EXPECT_THROW(patch_set_to_json(ps), std::invalid_argument);
    ps = sample_patch_set();
    ps.corners[2].position[1] = bad;
    EXPECT_THROW(patch_set_to_json(ps), std::invalid_argument);
    ps = sample_patch_set();
    ps.model_size = bad;
    EXPECT_THROW(patch_set_to_json(ps), std::invalid_argument);
  }
}

TEST(PatchJson, WriteIsAtomicAndMatchesTheText) {
  TempDir dir;
  const std::string path = dir.file("patches.json");
  const PatchSet ps = sample_patch_set();
  write_patch_json(path, ps);
  EXPECT_EQ(read_text(path), patch_set_to_json(ps));
  // A failing export leaves the previous file untouched and no temporary file behind.
  PatchSet bad = ps;
  bad.patches[0].poles[5][2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(write_patch_json(path, bad), std::invalid_argument);
  EXPECT_EQ(read_text(path), patch_set_to_json(ps));
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"patches.json"});
  EXPECT_THROW(write_patch_json(dir.file("missing/dir/patches.json"), ps), WriteError);
}
