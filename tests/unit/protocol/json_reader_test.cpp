#include "protocol/json_reader.hpp"

#include <gtest/gtest.h>

namespace scatter {
namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ValidationError& e) {
    return e.what();
  }
  return "no error";
}

TEST(JsonReader, ReadsTypedFieldsWithDefaults) {
  auto j = nlohmann::json::parse(R"({"a": 2.5, "n": 3, "s": "x", "v": [1, 2, 3], "c": 0.5})");
  JsonObject o(j, "root");
  EXPECT_EQ(o.number("a", std::nullopt, {0, 10}), 2.5);
  EXPECT_EQ(o.integer("n", std::nullopt, {0, 10}), 3);
  EXPECT_EQ(o.string("s", std::nullopt), "x");
  EXPECT_EQ(o.vec3("v", std::nullopt, {0, 10}), (Vec3{1, 2, 3}));
  EXPECT_EQ(o.rgb("c", std::nullopt, {0, 1}), (Vec3{0.5, 0.5, 0.5}));
  EXPECT_EQ(o.number("missing", 7.0, {0, 10}), 7.0);
  EXPECT_NO_THROW(o.finish());
}

TEST(JsonReader, ErrorsNameTheFieldAndTheProblem) {
  auto j =
      nlohmann::json::parse(R"({"a": -1, "n": 2.5, "v": [1, "x", 3], "t": "cube", "extra": 1})");
  JsonObject o(j, "root");
  EXPECT_EQ(error_of([&] {
              o.number("a", std::nullopt, {0, 10});
            }),
            "root.a: must be in [0, 10], got -1");
  EXPECT_EQ(error_of([&] {
              o.integer("n", std::nullopt, {0, 10});
            }),
            "root.n: must be an integer, got 2.5");
  EXPECT_EQ(error_of([&] {
              o.vec3("v", std::nullopt, {0, 10});
            }),
            "root.v[1]: must be a number, got string");
  EXPECT_EQ(error_of([&] {
              o.choice("t", {"sphere", "box"}, std::nullopt);
            }),
            "root.t: must be one of sphere, box; got \"cube\"");
  EXPECT_EQ(error_of([&] {
              o.number("absent", std::nullopt, {0, 1});
            }),
            "root.absent: is required");
  EXPECT_EQ(error_of([&] { o.finish(); }), "root.extra: is not a known field");
}

TEST(JsonReader, RejectsNonFiniteAndNonObjects) {
  nlohmann::json j = {{"x", std::numeric_limits<double>::infinity()}};
  JsonObject o(j, "r");
  EXPECT_NE(error_of([&] {
              o.number("x", std::nullopt, {-1e300, 1e300});
            }).find("r.x"),
            std::string::npos);
  EXPECT_EQ(error_of([] { JsonObject(nlohmann::json::array(), "r"); }),
            "r: must be an object, got array");
}

TEST(JsonReader, MalformedTextReportsPosition) {
  std::string e = error_of([] { parse_json("{\"a\": [1, 2", "scene.json"); });
  EXPECT_NE(e.find("scene.json: is not valid JSON"), std::string::npos) << e;
  EXPECT_NE(e.find("line 1"), std::string::npos) << e;
}

TEST(JsonReader, NumbersPastADoublesRangeAreValidationErrors) {
  try {
    parse_json(R"({"exposure": 1e999})", "body");
    FAIL() << "accepted 1e999";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "body");
    EXPECT_NE(std::string(e.what()).find("is not valid JSON"), std::string::npos) << e.what();
  }
}

TEST(JsonReader, NestingIsBoundedBeforeAnythingRecurses) {
  auto nested = [](int levels) { return std::string(levels, '[') + std::string(levels, ']'); };
  EXPECT_NO_THROW(parse_json(nested(kMaxJsonDepth), "body"));
  EXPECT_THROW(parse_json(nested(kMaxJsonDepth + 1), "body"), ValidationError);
  try {
    parse_json("{\"a\": " + nested(100000) + "}",
               "body");  // would exhaust a recursive walker's stack
    FAIL() << "accepted 100000 levels";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "body");
    EXPECT_NE(std::string(e.what()).find("deeper than 64 levels"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace scatter
