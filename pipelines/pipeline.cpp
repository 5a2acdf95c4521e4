#include "pipelines/pipeline.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "core/errors.hpp"
#include "pipelines/registry.hpp"

namespace scatter {

std::string to_string(Terms t) {
  switch (t) {
    case Terms::Surface:
      return "surface";
    case Terms::Single:
      return "single";
    case Terms::Multiple:
      return "multiple";
    case Terms::All:
      return "all";
  }
  return "all";
}

Terms parse_terms(const std::string& s) {
  for (Terms t : {Terms::Surface, Terms::Single, Terms::Multiple, Terms::All})
    if (to_string(t) == s) return t;
  throw ValidationError("terms",
                        "must be one of surface, single, multiple, all; got \"" + s + "\"");
}

void to_json(nlohmann::json& j, const StagePlan& s) {
  j = {{"stage", s.name}, {"run", s.run}, {"reason", s.reason}};
}

void to_json(nlohmann::json& j, const PlanOption& o) {
  j = {{"pipeline", o.pipeline},
       {"settings", o.settings},
       {"expected_error", o.expected_error},
       {"expected_seconds", o.expected_seconds},
       {"note", o.note}};
}

void to_json(nlohmann::json& j, const Plan& p) {
  j = {{"pipeline", p.pipeline}, {"terms", to_string(p.terms)}, {"stages", p.stages}};
  if (p.expected_error) j["expected_error"] = *p.expected_error;
  if (p.expected_seconds) j["expected_seconds"] = *p.expected_seconds;
  if (!p.alternatives.empty()) j["alternatives"] = p.alternatives;
}

double SettingsReader::number(const std::string& key, double fallback, double lo, double hi) {
  used_.insert(key);
  auto it = settings_.find(key);
  if (it == settings_.end()) return fallback;
  if (!(it->second >= lo && it->second <= hi)) {
    std::ostringstream msg;
    msg << "must be in [" << exact_number(lo) << ", " << exact_number(hi) << "] for pipeline "
        << pipeline_ << ", got " << exact_number(it->second);
    throw ValidationError("settings." + key, msg.str());
  }
  return it->second;
}

int SettingsReader::integer(const std::string& key, int fallback, int lo, int hi) {
  double v = number(key, fallback, lo, hi);
  if (v != std::floor(v)) throw ValidationError("settings." + key, "must be an integer");
  return static_cast<int>(v);
}

void SettingsReader::finish() const {
  for (const auto& [key, value] : settings_)
    if (!used_.count(key))
      throw ValidationError("settings." + key, "is not a setting of pipeline " + pipeline_);
}

StagePlan& plan_stage(Plan& plan, const std::string& name) {
  for (StagePlan& s : plan.stages)
    if (s.name == name) return s;
  throw std::logic_error("plan " + plan.pipeline + " has no stage " + name);
}

std::string Pipeline::name() const {
  return info().name;
}
std::vector<Terms> Pipeline::supported_terms() const {
  return info().terms;
}
std::vector<std::pair<std::string, double>> Pipeline::bake_stages() const {
  return info().bake_stages;
}

std::string short_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

std::string exact_number(double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

void require_terms(const Pipeline& pipeline, Terms terms) {
  require_terms(pipeline.info(), terms);
}

}  // namespace scatter
