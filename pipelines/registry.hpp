// The registry: one PipelineInfo per pipeline, defined in the pipeline's folder
// (pipelines/<name>/<name>_info.cpp), listed once in registry.cpp. What a client, the edge's
// validation or the cost estimate needs to know about a pipeline is here, without an instance and
// without a GPU: its terms, its settings table, its bake stages, its quality presets, how to make
// one and what a request will cost.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "pipelines/cost.hpp"
#include "pipelines/pipeline.hpp"
#include "pipelines/settings_table.hpp"

namespace scatter {

// A named preset of settings a client offers ("draft", "normal", "high"); "normal" is the
// pipeline's defaults.
struct Quality {
  std::string name;
  Settings settings;
};

struct PipelineInfo {
  std::string name;
  std::string summary;               // one line: what it renders and how
  std::string method;                // where the method is described (paper, docs/pipelines/)
  std::vector<Terms> terms;          // what it can render
  Terms default_terms = Terms::All;  // what a live view asks of it unless told
  std::vector<SettingInfo> settings;
  // Throws ValidationError for a setting render() would reject (unknown key, range, kind, rule).
  std::function<void(const Settings&)> validate;
  std::vector<std::pair<std::string, double>> bake_stages;  // empty: it bakes nothing
  // The key of the product a bake of the scene with these settings makes (pipelines that bake):
  // the bake job's id, known before the job runs.
  std::function<std::string(const Scene&, const Settings&)> bake_key;
  std::vector<Quality> qualities;
  // Frame-only settings the live view's reduced frames take while the user drags, once at their
  // smallest size and still over the frame-time budget (server/reduced_frames.hpp); empty: the
  // draft quality's frame-only settings.
  Settings moving;
  std::vector<std::string> delegates;  // auto: the pipelines it may choose
  std::function<std::unique_ptr<Pipeline>(gpu::Gpu&, BakeCache*)> make;
  // What a render (bake: a bake) will cost, before it runs (pipelines/cost.hpp).
  std::function<CostEstimate(const Scene&, const RenderRequest&, bool bake)> estimate;

  bool bakes() const { return !bake_stages.empty(); }
  bool renders(Terms t) const;
};

// `info` completed from pipeline P and its settings table: name, settings, validate, make (P's
// constructor takes the Gpu, and the BakeCache where it has one) and estimate (P::estimate).
template <class P, class S>
PipelineInfo describe(const SettingsTable<S>& table, PipelineInfo info) {
  info.name = table.pipeline();
  info.settings = table.info();
  info.validate = [&table](const Settings& s) { table.read(s); };
  info.make = [](gpu::Gpu& gpu, BakeCache* cache) -> std::unique_ptr<Pipeline> {
    if constexpr (std::is_constructible_v<P, gpu::Gpu&, BakeCache*>)
      return std::make_unique<P>(gpu, cache);
    else
      return std::make_unique<P>(gpu);
  };
  info.estimate = &P::estimate;
  return info;
}

// Every pipeline, in the order clients list them.
const std::vector<const PipelineInfo*>& registry();
// Throws ValidationError (field "pipeline") for an unknown name, listing the known ones.
const PipelineInfo& pipeline_info(const std::string& name);
// Throws ValidationError (field "terms") unless `info` renders `terms`.
void require_terms(const PipelineInfo& info, Terms terms);

void to_json(nlohmann::json& j, const PipelineInfo& p);
// The settings table as Markdown (docs/pipelines/<name>.md's generated section).
std::string settings_markdown(const PipelineInfo& p);

}  // namespace scatter
