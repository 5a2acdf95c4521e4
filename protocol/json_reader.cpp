#include "protocol/json_reader.hpp"

#include <cmath>
#include <sstream>

namespace scatter {
namespace {

std::string type_name(const nlohmann::json& v) {
  return v.type_name();
}

std::string format_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string range_text(Range r) {
  return "[" + format_number(r.lo) + ", " + format_number(r.hi) + "]";
}

double checked_number(const nlohmann::json& v, const std::string& path, Range range) {
  if (!v.is_number()) throw ValidationError(path, "must be a number, got " + type_name(v));
  double d = v.get<double>();
  if (!std::isfinite(d) || d < range.lo || d > range.hi)
    throw ValidationError(path, "must be in " + range_text(range) + ", got " + format_number(d));
  return d;
}

}  // namespace

JsonObject::JsonObject(const nlohmann::json& value, std::string path)
    : value_(value), path_(std::move(path)) {
  if (!value_.is_object())
    throw ValidationError(path_, "must be an object, got " + type_name(value_));
}

bool JsonObject::has(std::string_view key) const {
  return value_.contains(key);
}

std::string JsonObject::path(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

const nlohmann::json* JsonObject::find(std::string_view key, bool required) {
  auto it = value_.find(key);
  if (it == value_.end()) {
    if (required) throw ValidationError(path(key), "is required");
    return nullptr;
  }
  used_.emplace(key);
  return &*it;
}

double JsonObject::number(std::string_view key, std::optional<double> fallback, Range range) {
  const auto* v = find(key, !fallback);
  return v ? checked_number(*v, path(key), range) : *fallback;
}

int JsonObject::integer(std::string_view key, std::optional<int> fallback, Range range) {
  const auto* v = find(key, !fallback);
  if (!v) return *fallback;
  if (!v->is_number_integer() &&
      !(v->is_number() && std::floor(v->get<double>()) == v->get<double>()))
    throw ValidationError(path(key), "must be an integer, got " + v->dump());
  return static_cast<int>(checked_number(*v, path(key), range));
}

bool JsonObject::boolean(std::string_view key, std::optional<bool> fallback) {
  const auto* v = find(key, !fallback);
  if (!v) return *fallback;
  if (!v->is_boolean()) throw ValidationError(path(key), "must be true or false, got " + v->dump());
  return v->get<bool>();
}

std::string JsonObject::string(std::string_view key, std::optional<std::string> fallback) {
  const auto* v = find(key, !fallback);
  if (!v) return *fallback;
  if (!v->is_string()) throw ValidationError(path(key), "must be a string, got " + type_name(*v));
  return v->get<std::string>();
}

std::string JsonObject::choice(std::string_view key, const std::vector<std::string>& choices,
                               std::optional<std::string> fallback) {
  std::string s = string(key, std::move(fallback));
  for (const auto& c : choices)
    if (c == s) return s;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  throw ValidationError(path(key), "must be one of " + list + "; got \"" + s + "\"");
}

Vec3 JsonObject::vec3(std::string_view key, std::optional<Vec3> fallback, Range range) {
  const auto* v = find(key, !fallback);
  if (!v) return *fallback;
  if (!v->is_array() || v->size() != 3)
    throw ValidationError(path(key), "must be an array of 3 numbers, got " + v->dump());
  Vec3 r;
  for (int i = 0; i < 3; ++i)
    r[i] = checked_number((*v)[i], path(key) + "[" + std::to_string(i) + "]", range);
  return r;
}

Vec3 JsonObject::rgb(std::string_view key, std::optional<Vec3> fallback, Range range) {
  auto it = value_.find(key);
  if (it != value_.end() && it->is_number()) {
    used_.emplace(key);
    double d = checked_number(*it, path(key), range);
    return {d, d, d};
  }
  return vec3(key, fallback, range);
}

std::vector<double> JsonObject::numbers(std::string_view key, size_t min_len, size_t max_len,
                                        Range range) {
  const auto& a = array(key, min_len, max_len);
  std::vector<double> r;
  for (size_t i = 0; i < a.size(); ++i)
    r.push_back(checked_number(a[i], path(key) + "[" + std::to_string(i) + "]", range));
  return r;
}

JsonObject JsonObject::object(std::string_view key) {
  return JsonObject(*find(key, true), path(key));
}

std::optional<JsonObject> JsonObject::optional_object(std::string_view key) {
  const auto* v = find(key, false);
  if (!v) return std::nullopt;
  return JsonObject(*v, path(key));
}

const nlohmann::json& JsonObject::array(std::string_view key, size_t min_len, size_t max_len) {
  const auto* v = find(key, true);
  if (!v->is_array()) throw ValidationError(path(key), "must be an array, got " + type_name(*v));
  if (v->size() < min_len || v->size() > max_len)
    throw ValidationError(path(key), "must have " + std::to_string(min_len) + " to " +
                                         std::to_string(max_len) + " elements, got " +
                                         std::to_string(v->size()));
  return *v;
}

void JsonObject::finish() const {
  for (const auto& [k, v] : value_.items())
    if (!used_.count(k)) throw ValidationError(path(k), "is not a known field");
}

nlohmann::json parse_json(std::string_view text, const std::string& what, int max_depth) {
  auto bounded = [&](int depth, nlohmann::json::parse_event_t event, nlohmann::json&) {
    bool opens = event == nlohmann::json::parse_event_t::object_start ||
                 event == nlohmann::json::parse_event_t::array_start;
    if (opens && depth >= max_depth)
      throw ValidationError(
          what, "nests arrays and objects deeper than " + std::to_string(max_depth) + " levels");
    return true;
  };
  try {
    return nlohmann::json::parse(text, bounded);
  } catch (const nlohmann::json::exception& e) {
    // Malformed text (parse_error, with the byte offset) and numbers past a double's range
    // (out_of_range, "1e999"); strip the library's "[json.exception...]" prefix.
    std::string msg = e.what();
    auto pos = msg.find("] ");
    throw ValidationError(
        what, "is not valid JSON: " + (pos == std::string::npos ? msg : msg.substr(pos + 2)));
  }
}

}  // namespace scatter
