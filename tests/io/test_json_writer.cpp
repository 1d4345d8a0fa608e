// io/json_writer: the layouts and number policies the project's JSON documents use, checked
// against texts written out by hand from the JSON grammar (RFC 8259) and the layout asked for.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/json_writer.h"

using namespace subd2nurbs;

namespace {
JsonWriter spaced() { return JsonWriter(JsonWriter::Numbers::Report, JsonWriter::Spacing::Spaced, "report"); }
JsonWriter compact() { return JsonWriter(JsonWriter::Numbers::Exact, JsonWriter::Spacing::Compact, "test JSON"); }
}  // namespace

TEST(JsonWriter, InlineObjectsAndArraysWithEitherSpacing) {
  JsonWriter w = spaced();
  w.begin_object();
  w.key("a").integer(1);
  w.key("b").begin_array().integer(2).boolean(true).null().end_array();
  w.key("c").begin_object().end_object();
  w.end_object();
  EXPECT_EQ(w.text(), R"({"a": 1, "b": [2, true, null], "c": {}})");
  JsonWriter c = compact();
  c.begin_object().key("a").integers(std::vector<int>{1, 2}).key("b").string("x").end_object();
  EXPECT_EQ(c.text(), R"({"a":[1,2],"b":"x"})");
}

TEST(JsonWriter, ItemsOneALineAndLineBreaks) {
  JsonWriter w = spaced();
  w.begin_object(2, 0);
  w.key("x").integer(1);
  w.key("o").begin_object();
  w.key("p").integer(2);
  w.break_line(4).key("list").begin_array(6, 4).integer(3).integer(4).end_array();
  w.break_line(4).key("empty").begin_array(6, 4).end_array();
  w.end_object();
  w.end_object();
  EXPECT_EQ(w.text(), "{\n  \"x\": 1,\n  \"o\": {\"p\": 2,\n    \"list\": [\n      3,\n      4\n    ],\n"
                      "    \"empty\": []}\n}");
}

TEST(JsonWriter, StringsAreEscaped) {
  EXPECT_EQ(JsonWriter::quoted("a\"b\\c\nd\te\x01"), "\"a\\\"b\\\\c\\nd\\te\\u0001\"");
  JsonWriter w = spaced();
  w.begin_array().string("tab\there").end_array();
  EXPECT_EQ(w.text(), "[\"tab\\there\"]");
}

TEST(JsonWriter, ReportNumbersAreExactDoublesOrNull) {
  JsonWriter w = spaced();
  const double third = 1.0 / 3;
  w.begin_array().number(third).number(0.5).number(-0.0).number(std::nan("")).number(HUGE_VAL).end_array();
  // %.17g round-trips every double; JSON has no NaN or infinity: null.
  EXPECT_EQ(std::stod(w.text().substr(1, w.text().find(',') - 1)), third);
  EXPECT_EQ(w.text().substr(w.text().find(',')), ", 0.5, -0, null, null]");
  EXPECT_EQ(JsonWriter::report_number(std::numeric_limits<double>::infinity()), "null");
}

TEST(JsonWriter, ExactNumbersRefuseNonFiniteValuesAndKeepNegativeZero) {
  JsonWriter w = compact();
  w.begin_array().number(-0.0).number(2.5).end_array();
  EXPECT_EQ(w.text(), "[-0.0,2.5]");
  JsonWriter bad = compact();
  bad.begin_array();
  try {
    bad.number(std::nan(""), "poles");
    FAIL() << "a NaN was written";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "test JSON: non-finite value in poles");
  }
}

TEST(JsonWriter, ClosingWhatIsNotOpenIsALogicError) {
  JsonWriter w = spaced();
  EXPECT_THROW(w.end_object(), std::logic_error);
}
