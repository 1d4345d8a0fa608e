// The usda (USD text) parser: tokens, values, metadata, prims, attributes, variant sets, into
// the layer model of io/usd_layer.h. Only what a cage needs is kept; everything else the grammar
// allows (relationships, connections, dictionaries, doc strings, splines) is parsed and skipped
// so that real files read. Errors name the file and line.
#include <cstring>
#include <string>
#include <string_view>

#include "io/input_error.h"
#include "io/input_file.h"
#include "io/usd_parsers.h"

namespace subd2nurbs::usd {

namespace {

struct Token {
  enum class Kind { End, Word, Number, String, Path, Asset, Punct } kind = Kind::End;
  std::string text;
  int line = 0;
};

bool is_word_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_' || c == '!'; }
bool is_word_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == ':' || c == '.' || c == '!' || c == '-';
}

class Parser {
 public:
  Parser(std::string_view text, const std::string& name, const Limits& limits, Layer& layer)
      : text_(text), name_(name), limits_(limits), layer_(layer) {}

  void parse() {
    // Header: "#usda 1.0".
    if (text_.substr(0, 5) != "#usda")
      throw InputError(name_, 1, "not a USD text file: the first line is not '#usda 1.0'");
    std::size_t eol = text_.find('\n');
    layer_.version = std::string(trim(text_.substr(5, eol == std::string_view::npos ? text_.npos : eol - 5)));
    layer_.encoding = "usda";
    advance();
    if (is_punct("(")) parse_layer_metadata();
    while (tok_.kind != Token::Kind::End) parse_statement(layer_.root, 0);
  }

 private:
  static std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return s;
  }

  [[noreturn]] void fail(const std::string& message, int line = 0) const {
    throw InputError(name_, line > 0 ? line : tok_.line, message);
  }

  std::string describe(const Token& t) const {
    if (t.kind == Token::Kind::End) return "the end of the file";
    return "'" + printable(t.text, 40) + "'";
  }

  // --- tokens --------------------------------------------------------------------------------

  void skip_space() {
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (c == '\n') {
        ++line_;
        ++pos_;
      } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
        ++pos_;
      } else if (c == '#') {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
      } else {
        break;
      }
    }
  }

  void advance() {
    skip_space();
    tok_ = Token{};
    tok_.line = line_;
    if (pos_ >= text_.size()) return;
    const char c = text_[pos_];
    if (c == '"' || c == '\'') {
      tok_.kind = Token::Kind::String;
      read_string(c);
    } else if (c == '<') {
      const std::size_t end = text_.find('>', pos_ + 1);
      if (end == std::string_view::npos) fail("a path '<' is not closed by '>'");
      tok_.kind = Token::Kind::Path;
      tok_.text = std::string(text_.substr(pos_ + 1, end - pos_ - 1));
      count_lines(pos_, end);
      pos_ = end + 1;
    } else if (c == '@') {
      tok_.kind = Token::Kind::Asset;
      const bool triple = text_.compare(pos_, 3, "@@@") == 0;
      const std::string_view close = triple ? "@@@" : "@";
      const std::size_t start = pos_ + close.size();
      const std::size_t end = text_.find(close, start);
      if (end == std::string_view::npos) fail("an asset path '@' is not closed");
      tok_.text = std::string(text_.substr(start, end - start));
      count_lines(pos_, end);
      pos_ = end + close.size();
    } else if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.') {
      tok_.kind = Token::Kind::Number;
      const std::size_t start = pos_;
      ++pos_;
      while (pos_ < text_.size() &&
             (std::isalnum(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '.' ||
              ((text_[pos_] == '-' || text_[pos_] == '+') && (text_[pos_ - 1] == 'e' || text_[pos_ - 1] == 'E'))))
        ++pos_;
      tok_.text = std::string(text_.substr(start, pos_ - start));
    } else if (is_word_start(c)) {
      tok_.kind = Token::Kind::Word;
      const std::size_t start = pos_;
      while (pos_ < text_.size() && is_word_char(text_[pos_])) ++pos_;
      tok_.text = std::string(text_.substr(start, pos_ - start));
    } else if (std::strchr("()[]{}=,:;&", c) != nullptr) {
      tok_.kind = Token::Kind::Punct;
      tok_.text = std::string(1, c);
      ++pos_;
    } else {
      fail("unexpected character " + printable(std::string_view(&text_[pos_], 1)));
    }
  }

  void count_lines(std::size_t from, std::size_t to) {
    for (std::size_t i = from; i < to && i < text_.size(); ++i)
      if (text_[i] == '\n') ++line_;
  }

  void read_string(char quote) {
    const bool triple = pos_ + 2 < text_.size() && text_[pos_ + 1] == quote && text_[pos_ + 2] == quote;
    pos_ += triple ? 3 : 1;
    std::string out;
    while (true) {
      if (pos_ >= text_.size()) fail("a string is not closed", tok_.line);
      const char c = text_[pos_];
      if (triple) {
        if (c == quote && pos_ + 2 < text_.size() && text_[pos_ + 1] == quote && text_[pos_ + 2] == quote) {
          pos_ += 3;
          break;
        }
      } else if (c == quote) {
        ++pos_;
        break;
      } else if (c == '\n') {
        fail("a string is not closed on its line", tok_.line);
      }
      if (c == '\n') ++line_;
      if (c == '\\' && pos_ + 1 < text_.size()) {
        const char e = text_[pos_ + 1];
        out += e == 'n' ? '\n' : e == 't' ? '\t' : e;
        if (e == '\n') ++line_;
        pos_ += 2;
        continue;
      }
      out += c;
      ++pos_;
    }
    tok_.text = std::move(out);
  }

  bool is_punct(const char* p) const { return tok_.kind == Token::Kind::Punct && tok_.text == p; }
  bool is_word(const char* w) const { return tok_.kind == Token::Kind::Word && tok_.text == w; }

  void expect_punct(const char* p, const char* context) {
    if (!is_punct(p)) fail(std::string("expected '") + p + "' " + context + ", found " + describe(tok_));
    advance();
  }

  std::string take_string(const char* context) {
    if (tok_.kind != Token::Kind::String) fail(std::string("expected a quoted ") + context + ", found " + describe(tok_));
    std::string s = tok_.text;
    advance();
    return s;
  }

  std::string take_word(const char* context) {
    if (tok_.kind != Token::Kind::Word) fail(std::string("expected ") + context + ", found " + describe(tok_));
    std::string s = tok_.text;
    advance();
    return s;
  }

  void check_depth(int depth) const {
    if (depth > limits_.max_depth)
      fail("nesting deeper than " + std::to_string(limits_.max_depth) + " levels");
  }

  void count_values(std::size_t n) {
    values_ += static_cast<long>(n);
    if (values_ > limits_.max_values)
      fail("more than " + std::to_string(limits_.max_values) + " values in the file");
  }

  // --- values ------------------------------------------------------------------------------

  /// Parses one value, flattening tuples and lists into `out`. Returns the numbers it added.
  std::size_t parse_value(Value& out, int depth) {
    check_depth(depth);
    const std::size_t before = out.numbers.size();
    switch (tok_.kind) {
      case Token::Kind::Number: {
        double x = 0;
        if (!parse_double(tok_.text, x)) fail("malformed number " + describe(tok_));
        out.kind = Value::Kind::Numbers;
        out.numbers.push_back(x);
        count_values(1);
        advance();
        break;
      }
      case Token::Kind::String:
      case Token::Kind::Path:
      case Token::Kind::Asset:
        if (out.kind == Value::Kind::Numbers) fail("a list mixes numbers and strings");
        out.kind = Value::Kind::Strings;
        out.strings.push_back(tok_.text);
        count_values(1);
        advance();
        if (tok_.kind == Token::Kind::Path) advance();  // @asset@</path> in a list
        if (is_punct("(")) skip_group(depth + 1);       // a reference's layer offset
        break;
      case Token::Kind::Word:
        if (tok_.text == "None") {
          advance();
        } else if (tok_.text == "true" || tok_.text == "false") {
          out.kind = Value::Kind::Numbers;
          out.numbers.push_back(tok_.text == "true" ? 1 : 0);
          count_values(1);
          advance();
        } else if (tok_.text == "inf" || tok_.text == "nan") {
          double x = 0;
          parse_double(tok_.text, x);
          out.kind = Value::Kind::Numbers;
          out.numbers.push_back(x);
          count_values(1);
          advance();
        } else {
          // An unquoted identifier (a token in some metadata): kept as a string.
          if (out.kind == Value::Kind::Numbers) fail("a list mixes numbers and strings");
          out.kind = Value::Kind::Strings;
          out.strings.push_back(tok_.text);
          count_values(1);
          advance();
        }
        break;
      case Token::Kind::Punct:
        if (is_punct("(") || is_punct("[")) {
          const bool list = is_punct("[");
          const char* close = list ? "]" : ")";
          if (list) out.array = true;
          advance();
          bool first = true;
          while (!is_punct(close)) {
            const std::size_t n = parse_value(out, depth + 1);
            if (first && list) out.width = static_cast<int>(std::max<std::size_t>(n, 1));
            first = false;
            if (is_punct(",")) advance();
            else if (!is_punct(close)) fail(std::string("expected ',' or '") + close + "' in a value, found " + describe(tok_));
          }
          advance();
          if (!list && depth == 0) out.width = static_cast<int>(out.numbers.size() - before);
        } else if (is_punct("{")) {
          skip_group(depth + 1);
        } else {
          fail("expected a value, found " + describe(tok_));
        }
        break;
      case Token::Kind::End:
        fail("expected a value, found the end of the file");
    }
    return out.numbers.size() - before;
  }

  /// Skips a balanced (...), [...] or {...} group.
  void skip_group(int depth) {
    check_depth(depth);
    const std::string open = tok_.text;
    const char* close = open == "(" ? ")" : open == "[" ? "]" : "}";
    advance();
    while (!is_punct(close)) {
      if (tok_.kind == Token::Kind::End) fail(std::string("a '") + open + "' is not closed by '" + close + "'");
      if (is_punct("(") || is_punct("[") || is_punct("{")) skip_group(depth + 1);
      else advance();
    }
    advance();
  }

  /// A dictionary `{ type key = value ... }`; string-valued entries go to `strings`.
  void parse_dictionary(std::map<std::string, std::string>* strings, int depth) {
    check_depth(depth);
    expect_punct("{", "to open a dictionary");
    while (!is_punct("}")) {
      if (tok_.kind == Token::Kind::End) fail("a dictionary '{' is not closed");
      const std::string type = take_word("a type in a dictionary");
      if (is_punct("[")) {
        advance();
        expect_punct("]", "after '[' in a type");
      }
      std::string key;
      if (tok_.kind == Token::Kind::String || tok_.kind == Token::Kind::Word) {
        key = tok_.text;
        advance();
      } else {
        fail("expected a key in a dictionary, found " + describe(tok_));
      }
      expect_punct("=", "after a dictionary key");
      if (type == "dictionary") {
        parse_dictionary(nullptr, depth + 1);
      } else {
        Value v;
        parse_value(v, depth + 1);
        if (strings && v.kind == Value::Kind::Strings && v.strings.size() == 1) (*strings)[key] = v.strings[0];
      }
      if (is_punct(";") || is_punct(",")) advance();
    }
    advance();
  }

  // --- metadata ------------------------------------------------------------------------------

  void parse_layer_metadata() {
    advance();  // (
    while (!is_punct(")")) {
      if (tok_.kind == Token::Kind::End) fail("the layer's metadata '(' is not closed");
      if (tok_.kind == Token::Kind::String) {  // the layer's doc string
        advance();
        continue;
      }
      std::string key = take_word("a metadata name");
      if (key == "prepend" || key == "append" || key == "add" || key == "delete" || key == "reorder")
        key = take_word("a metadata name");
      expect_punct("=", "after a metadata name");
      if (is_punct("{")) {
        parse_dictionary(nullptr, 1);
        continue;
      }
      const int line = tok_.line;
      Value v;
      parse_value(v, 1);
      if (key == "metersPerUnit" && v.kind == Value::Kind::Numbers && !v.numbers.empty())
        layer_.meters_per_unit = v.numbers[0];
      else if (key == "upAxis" && v.kind == Value::Kind::Strings && !v.strings.empty())
        layer_.up_axis = v.strings[0];
      else if (key == "defaultPrim" && v.kind == Value::Kind::Strings && !v.strings.empty())
        layer_.default_prim = v.strings[0];
      else if (key == "subLayers" && !v.strings.empty())
        layer_.notes.push_back("line " + std::to_string(line) + ": the sublayers (" + printable(v.strings[0], 60) +
                               (v.strings.size() > 1 ? ", ..." : "") + ") are not read");
      if (is_punct(";")) advance();
    }
    advance();
  }

  void parse_prim_metadata(PrimSpec& prim, int depth) {
    advance();  // (
    while (!is_punct(")")) {
      if (tok_.kind == Token::Kind::End) fail("a prim's metadata '(' is not closed");
      if (tok_.kind == Token::Kind::String) {  // doc string
        advance();
        continue;
      }
      std::string op;
      std::string key = take_word("a metadata name");
      if (key == "prepend" || key == "append" || key == "add" || key == "delete" || key == "reorder") {
        op = key;
        key = take_word("a metadata name");
      }
      expect_punct("=", "after a metadata name");
      if (key == "variants") {
        std::map<std::string, std::string> selection;
        parse_dictionary(&selection, depth + 1);
        for (const auto& [set, variant] : selection) prim.variant_selection[set] = variant;
      } else if (is_punct("{")) {
        parse_dictionary(nullptr, depth + 1);
      } else if (key == "references" || key == "payload" || key == "inherits" || key == "specializes") {
        parse_references(prim, key, op, depth + 1);
      } else {
        Value v;
        parse_value(v, depth + 1);
        if (key == "instanceable" && v.kind == Value::Kind::Numbers && !v.numbers.empty())
          prim.instanceable = v.numbers[0] != 0;
        else if (key == "active" && v.kind == Value::Kind::Numbers && !v.numbers.empty())
          prim.active = v.numbers[0] != 0 ? 1 : 0;
        else if (key == "variantSets" && op != "delete")
          for (const std::string& s : v.strings) prim.variant_set_or_add(s);
      }
      if (is_punct(";")) advance();
    }
    advance();
  }

  /// references / payload / inherits / specializes: `</path>`, `@asset@`, `@asset@</path>`, a
  /// list of those (each with an optional `(offset = ...)`), or None.
  void parse_references(PrimSpec& prim, const std::string& key, const std::string& op, int depth) {
    check_depth(depth);
    const bool list = is_punct("[");
    if (list) advance();
    while (true) {
      if (list && is_punct("]")) {
        advance();
        break;
      }
      std::string asset, path;
      if (is_word("None")) {
        advance();
        if (!list) break;
      } else {
        if (tok_.kind == Token::Kind::Asset) {
          asset = tok_.text;
          advance();
        }
        if (tok_.kind == Token::Kind::Path) {
          path = tok_.text;
          advance();
        }
        if (asset.empty() && path.empty()) fail("expected a reference (@asset@ or </path>), found " + describe(tok_));
        if (is_punct("(")) skip_group(depth + 1);
        if (op != "delete") {
          if (!asset.empty()) prim.external_references.push_back(key + " @" + asset + "@");
          else if (key == "references" || key == "payload") prim.internal_references.push_back(path);
          else prim.external_references.push_back(key + " <" + path + ">");
        }
      }
      if (!list) break;
      if (is_punct(",")) advance();
      else if (!is_punct("]")) fail("expected ',' or ']' in a reference list, found " + describe(tok_));
    }
  }

  // --- prims and properties ------------------------------------------------------------------

  void count_spec() {
    if (++specs_ > limits_.max_prims) fail("more than " + std::to_string(limits_.max_prims) + " prims and properties");
  }

  /// A statement inside a prim (or variant) body, or at the root.
  void parse_statement(PrimSpec& parent, int depth) {
    check_depth(depth);
    count_spec();
    if (is_word("def") || is_word("over") || is_word("class")) {
      parse_prim(parent, depth);
    } else if (is_word("variantSet")) {
      parse_variant_set(parent, depth);
    } else if (is_word("reorder")) {
      advance();
      take_word("nameChildren or properties after 'reorder'");
      expect_punct("=", "after 'reorder ...'");
      Value v;
      parse_value(v, depth + 1);
    } else if (&parent == &layer_.root) {
      fail("expected 'def', 'over' or 'class' at the root of the layer, found " + describe(tok_));
    } else {
      parse_property(parent, depth);
    }
  }

  void parse_prim(PrimSpec& parent, int depth) {
    const int line = tok_.line;
    const Specifier specifier = tok_.text == "def" ? Specifier::Def : tok_.text == "over" ? Specifier::Over : Specifier::Class;
    advance();
    std::string type_name;
    if (tok_.kind == Token::Kind::Word) type_name = take_word("a prim type");
    const std::string name = take_string("prim name");
    if (name.empty() || name.find('/') != std::string::npos)
      fail("invalid prim name '" + printable(name, 60) + "'", line);
    PrimSpec& prim = parent.child_or_add(name);
    if (specifier == Specifier::Def || prim.line == 0) prim.specifier = specifier;
    if (!type_name.empty()) prim.type_name = type_name;
    if (prim.line == 0) prim.line = line;
    if (is_punct("(")) parse_prim_metadata(prim, depth + 1);
    expect_punct("{", "to open the prim's body");
    while (!is_punct("}")) {
      if (tok_.kind == Token::Kind::End) fail("the prim '" + printable(name, 60) + "' is not closed by '}'", line);
      parse_statement(prim, depth + 1);
    }
    advance();
  }

  void parse_variant_set(PrimSpec& prim, int depth) {
    const int line = tok_.line;
    advance();
    const std::string set_name = take_string("variant set name");
    expect_punct("=", "after the variant set's name");
    expect_punct("{", "to open the variant set");
    VariantSet& set = prim.variant_set_or_add(set_name);
    while (!is_punct("}")) {
      if (tok_.kind == Token::Kind::End) fail("the variant set '" + printable(set_name, 60) + "' is not closed", line);
      count_spec();
      const int variant_line = tok_.line;
      const std::string variant = take_string("variant name");
      PrimSpec* spec = nullptr;
      for (auto& [n, s] : set.variants)
        if (n == variant) spec = s.get();
      if (!spec) {
        set.variants.emplace_back(variant, std::make_unique<PrimSpec>());
        spec = set.variants.back().second.get();
        spec->name = variant;
        spec->line = variant_line;
      }
      if (is_punct("(")) parse_prim_metadata(*spec, depth + 1);
      expect_punct("{", "to open the variant's body");
      while (!is_punct("}")) {
        if (tok_.kind == Token::Kind::End) fail("the variant '" + printable(variant, 60) + "' is not closed", variant_line);
        parse_statement(*spec, depth + 2);
      }
      advance();
    }
    advance();
  }

  void parse_property(PrimSpec& prim, int depth) {
    const int line = tok_.line;
    bool uniform = false;
    if (is_word("custom")) advance();
    if (is_word("uniform") || is_word("varying") || is_word("config")) {
      uniform = tok_.text != "varying";
      advance();
    }
    if (is_word("rel")) {  // a relationship: name, optional targets and metadata
      advance();
      take_word("a relationship name");
      if (is_punct("=")) {
        advance();
        Value v;
        parse_value(v, depth + 1);
      }
      if (is_punct("(")) skip_group(depth + 1);
      return;
    }
    std::string type = take_word("a property (a type such as 'int[]' or 'def', 'over', 'rel')");
    if (is_punct("[")) {
      advance();
      expect_punct("]", "after '[' in a type");
      type += "[]";
    }
    std::string name = take_word("an attribute name");
    std::string suffix;
    const std::size_t dot = name.rfind('.');
    if (dot != std::string::npos) {
      suffix = name.substr(dot + 1);
      name.resize(dot);
    }
    (void)uniform;
    if (suffix == "connect" || suffix == "spline") {
      if (is_punct("=")) {
        advance();
        if (is_punct("{")) skip_group(depth + 1);
        else {
          Value v;
          parse_value(v, depth + 1);
        }
      }
      if (is_punct("(")) skip_group(depth + 1);
      return;
    }
    if (!suffix.empty() && suffix != "timeSamples") fail("unknown attribute suffix '." + printable(suffix, 30) + "'", line);
    Attribute& attribute = prim.attribute_or_add(name);
    attribute.type_name = type;
    attribute.line = line;
    if (is_punct("=")) {
      advance();
      if (suffix == "timeSamples") {
        parse_time_samples(attribute, depth + 1);
      } else {
        attribute.default_value = Value{};
        parse_value(attribute.default_value, 0);
        attribute.has_default = true;
      }
    }
    if (is_punct("(")) skip_group(depth + 1);
  }

  void parse_time_samples(Attribute& attribute, int depth) {
    expect_punct("{", "to open the time samples");
    while (!is_punct("}")) {
      if (tok_.kind != Token::Kind::Number) fail("expected a time in the time samples, found " + describe(tok_));
      double t = 0;
      if (!parse_double(tok_.text, t)) fail("malformed time " + describe(tok_));
      advance();
      expect_punct(":", "after a sample's time");
      Value v;
      parse_value(v, 0);
      (void)depth;
      attribute.samples.emplace_back(t, std::move(v));
      if (is_punct(",")) advance();
      else if (!is_punct("}")) fail("expected ',' or '}' in the time samples, found " + describe(tok_));
    }
    advance();
  }

  std::string_view text_;
  const std::string& name_;
  const Limits& limits_;
  Layer& layer_;
  std::size_t pos_ = 0;
  int line_ = 1;
  Token tok_;
  long values_ = 0;
  long specs_ = 0;
};

}  // namespace

void parse_usda(std::string_view text, const std::string& name, const Limits& limits, Layer& layer) {
  Parser(text, name, limits, layer).parse();
}

}  // namespace subd2nurbs::usd
