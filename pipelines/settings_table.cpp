#include "pipelines/settings_table.hpp"

#include <cstdio>

#include "protocol/json_reader.hpp"

namespace scatter {

std::string to_string(SettingKind k) {
  switch (k) {
    case SettingKind::Number:
      return "number";
    case SettingKind::Integer:
      return "integer";
    case SettingKind::Flag:
      return "flag";
  }
  return "number";
}

std::string to_string(Shapes::What w) {
  switch (w) {
    case Shapes::What::Frame:
      return "frame";
    case Shapes::What::Bake:
      return "bake";
    case Shapes::What::Kept:
      return "kept";
  }
  return "frame";
}

void to_json(nlohmann::json& j, const SettingInfo& s) {
  j = {{"key", s.key}, {"kind", to_string(s.kind)},          {"default", s.def}, {"min", s.lo},
       {"max", s.hi},  {"shapes", to_string(s.shapes.what)}, {"doc", s.doc}};
  if (s.shapes.what == Shapes::What::Kept) j["state"] = s.shapes.state;
  if (!s.allowed.empty()) j["allowed"] = s.allowed;
}

void check_allowed(const std::string& key, double v, const std::vector<double>& allowed) {
  std::string list;
  for (size_t i = 0; i < allowed.size(); ++i) {
    if (allowed[i] == v) return;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", allowed[i]);
    list += (i == 0 ? "" : i + 1 == allowed.size() ? " or " : ", ") + std::string(buf);
  }
  char got[32];
  std::snprintf(got, sizeof got, "%.10g", v);
  throw ValidationError("settings." + key, "must be " + list + ", got " + got);
}

}  // namespace scatter
