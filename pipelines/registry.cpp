#include "pipelines/registry.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "protocol/json_reader.hpp"

namespace scatter {

// Defined in each pipeline's folder (pipelines/<name>/<name>_info.cpp).
const PipelineInfo& auto_info();
const PipelineInfo& surface_info();
const PipelineInfo& reference_info();
const PipelineInfo& thickness_info();
const PipelineInfo& single_info();
const PipelineInfo& psf_info();
const PipelineInfo& lbl_info();

const std::vector<const PipelineInfo*>& registry() {
  static const std::vector<const PipelineInfo*> all = {
      &auto_info(),   &surface_info(), &reference_info(), &thickness_info(),
      &single_info(), &psf_info(),     &lbl_info()};
  return all;
}

const PipelineInfo& pipeline_info(const std::string& name) {
  for (const PipelineInfo* p : registry())
    if (p->name == name) return *p;
  std::string list;
  for (const PipelineInfo* p : registry()) list += (list.empty() ? "" : ", ") + p->name;
  throw ValidationError("pipeline", "unknown pipeline \"" + name + "\" (known: " + list + ")");
}

bool PipelineInfo::renders(Terms t) const {
  return std::find(terms.begin(), terms.end(), t) != terms.end();
}

void require_terms(const PipelineInfo& info, Terms terms) {
  if (info.renders(terms)) return;
  std::string list;
  for (Terms t : info.terms) list += (list.empty() ? "" : ", ") + to_string(t);
  throw ValidationError("terms", "pipeline " + info.name + " cannot render the " +
                                     to_string(terms) + " term (it renders: " + list + ")");
}

std::vector<std::string> pipeline_names() {
  std::vector<std::string> names;
  for (const PipelineInfo* p : registry()) names.push_back(p->name);
  return names;
}

std::unique_ptr<Pipeline> make_pipeline(const std::string& name, gpu::Gpu& gpu, BakeCache* cache) {
  return pipeline_info(name).make(gpu, cache);
}

void to_json(nlohmann::json& j, const PipelineInfo& p) {
  nlohmann::json terms = nlohmann::json::array(), stages = nlohmann::json::array(),
                 qualities = nlohmann::json::array();
  for (Terms t : p.terms) terms.push_back(to_string(t));
  for (const auto& [stage, weight] : p.bake_stages)
    stages.push_back({{"stage", stage}, {"weight", weight}});
  for (const Quality& q : p.qualities)
    qualities.push_back({{"name", q.name}, {"settings", q.settings}});
  j = {{"name", p.name},
       {"summary", p.summary},
       {"method", p.method},
       {"terms", terms},
       {"default_terms", to_string(p.default_terms)},
       {"bakes", p.bakes()},
       {"bake_stages", stages},
       {"settings", p.settings},
       {"qualities", qualities}};
  if (!p.moving.empty()) j["moving"] = p.moving;
  if (!p.delegates.empty()) j["delegates"] = p.delegates;
}

namespace {

std::string cell(double v, SettingKind k) {
  if (k == SettingKind::Flag) return v != 0 ? "1" : "0";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

// A table cell's text: a '|' would end the cell.
std::string escaped(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

}  // namespace

std::string settings_markdown(const PipelineInfo& p) {
  std::ostringstream md;
  if (p.settings.empty()) {
    md << "`" << p.name << "` has no settings.\n";
    return md.str();
  }
  md << "| setting | kind | default | range | shapes | what it does |\n| --- | --- | --- | --- | "
        "--- | --- |\n";
  for (const SettingInfo& s : p.settings) {
    std::string range;
    if (!s.allowed.empty()) {
      for (double v : s.allowed) range += (range.empty() ? "" : ", ") + cell(v, s.kind);
    } else {
      range =
          s.kind == SettingKind::Flag ? "0, 1" : cell(s.lo, s.kind) + " to " + cell(s.hi, s.kind);
    }
    std::string shapes = to_string(s.shapes.what);
    if (s.shapes.what == Shapes::What::Kept) shapes += " (" + s.shapes.state + ")";
    md << "| `" << s.key << "` | " << to_string(s.kind) << " | " << cell(s.def, s.kind) << " | "
       << range << " | " << shapes << " | " << escaped(s.doc) << " |\n";
  }
  return md.str();
}

}  // namespace scatter
