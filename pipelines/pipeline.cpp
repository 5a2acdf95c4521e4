#include "pipelines/pipeline.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/errors.hpp"
#include "pipelines/auto_pipeline.hpp"
#include "pipelines/lbl/lbl_pipeline.hpp"
#include "pipelines/psf/psf_pipeline.hpp"
#include "pipelines/reference/reference_pipeline.hpp"
#include "pipelines/surface/surface_pipeline.hpp"
#include "pipelines/single/single_pipeline.hpp"
#include "pipelines/thickness/thickness_pipeline.hpp"

namespace scatter {

std::string to_string(Terms t) {
  switch (t) {
    case Terms::Surface: return "surface";
    case Terms::Single: return "single";
    case Terms::Multiple: return "multiple";
    case Terms::All: return "all";
  }
  return "all";
}

Terms parse_terms(const std::string& s) {
  for (Terms t : {Terms::Surface, Terms::Single, Terms::Multiple, Terms::All})
    if (to_string(t) == s) return t;
  throw ValidationError("terms", "must be one of surface, single, multiple, all; got \"" + s + "\"");
}

void to_json(nlohmann::json& j, const StagePlan& s) {
  j = {{"stage", s.name}, {"run", s.run}, {"reason", s.reason}};
}

void to_json(nlohmann::json& j, const Plan& p) {
  j = {{"pipeline", p.pipeline}, {"terms", to_string(p.terms)}, {"stages", p.stages}};
}

double SettingsReader::number(const std::string& key, double fallback, double lo, double hi) {
  used_.insert(key);
  auto it = settings_.find(key);
  if (it == settings_.end()) return fallback;
  if (!(it->second >= lo && it->second <= hi)) {
    std::ostringstream msg;
    msg << "must be in [" << lo << ", " << hi << "] for pipeline " << pipeline_ << ", got "
        << it->second;
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

std::vector<std::string> pipeline_names() { return {"auto", "surface", "reference", "thickness", "single", "psf", "lbl"}; }

std::unique_ptr<Pipeline> make_pipeline(const std::string& name, gpu::Gpu& gpu, BakeCache* cache) {
  if (name == "auto") return std::make_unique<AutoPipeline>(gpu, cache);
  if (name == "surface") return std::make_unique<SurfacePipeline>(gpu);
  if (name == "reference") return std::make_unique<ReferencePipeline>(gpu);
  if (name == "thickness") return std::make_unique<ThicknessPipeline>(gpu);
  if (name == "single") return std::make_unique<SinglePipeline>(gpu, cache);
  if (name == "psf") return std::make_unique<PsfPipeline>(gpu);
  if (name == "lbl") return std::make_unique<LblPipeline>(gpu);
  std::string list;
  for (const auto& n : pipeline_names()) list += (list.empty() ? "" : ", ") + n;
  throw ValidationError("pipeline", "unknown pipeline \"" + name + "\" (known: " + list + ")");
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
  auto ok = pipeline.supported_terms();
  if (std::find(ok.begin(), ok.end(), terms) != ok.end()) return;
  std::string list;
  for (Terms t : ok) list += (list.empty() ? "" : ", ") + to_string(t);
  throw ValidationError("terms", "pipeline " + pipeline.name() + " cannot render the " +
                                     to_string(terms) + " term (it renders: " + list + ")");
}

}  // namespace scatter
