// Reads untrusted JSON objects field by field. Every problem becomes a ValidationError
// (core/errors.hpp) that names the field by its full path ("scene.medium.sigma_s[1]") and says
// what is wrong with it; fields that nobody read are rejected by finish(), so a misspelt key is an
// error, not a silent default.
#pragma once

#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.hpp"
#include "core/vec.hpp"

namespace scatter {

struct Range {
  double lo;
  double hi;
};
// Every finite number: for values whose range another check states (a pipeline's settings,
// checked against that pipeline's own ranges, so that the error names the limit that applies).
constexpr Range kAnyFinite{-std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};

class JsonObject {
 public:
  // Throws ValidationError unless `value` is an object.
  JsonObject(const nlohmann::json& value, std::string path);

  bool has(std::string_view key) const;
  std::string path(std::string_view key) const;

  double number(std::string_view key, std::optional<double> fallback, Range range);
  int integer(std::string_view key, std::optional<int> fallback, Range range);
  bool boolean(std::string_view key, std::optional<bool> fallback);
  std::string string(std::string_view key, std::optional<std::string> fallback);
  // One of `choices`; the error lists them.
  std::string choice(std::string_view key, const std::vector<std::string>& choices,
                     std::optional<std::string> fallback);
  // A 3-array of numbers, each in `range`.
  Vec3 vec3(std::string_view key, std::optional<Vec3> fallback, Range range);
  // Like vec3, but a single number stands for all three channels.
  Vec3 rgb(std::string_view key, std::optional<Vec3> fallback, Range range);
  // Array of numbers with a length in [min_len, max_len].
  std::vector<double> numbers(std::string_view key, size_t min_len, size_t max_len, Range range);
  JsonObject object(std::string_view key);
  std::optional<JsonObject> optional_object(std::string_view key);
  // Raw access for arrays of objects; the caller reads each element with its own JsonObject.
  const nlohmann::json& array(std::string_view key, size_t min_len, size_t max_len);

  // Throws for the first key that was never read.
  void finish() const;
  // The object itself (its canonical dump identifies what it describes).
  const nlohmann::json& value() const { return value_; }

 private:
  const nlohmann::json* find(std::string_view key, bool required);

  const nlohmann::json& value_;
  std::string path_;
  std::set<std::string, std::less<>> used_;
};

// The deepest nesting of arrays and objects that parse_json accepts: enough for any scene or
// message, and far from the recursion depth that would exhaust a thread's stack in code that walks
// the document.
constexpr int kMaxJsonDepth = 64;

// Parses untrusted text; throws ValidationError(what, ...) naming the parser's position for
// malformed input, and for nesting deeper than `max_depth` (checked in the parser's callback, as
// each level opens, before anything recurses over the document).
nlohmann::json parse_json(std::string_view text, const std::string& what,
                          int max_depth = kMaxJsonDepth);

}  // namespace scatter
