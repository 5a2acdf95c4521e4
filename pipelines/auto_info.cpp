// `auto` in the registry. It accepts the settings of thickness and reference (whose keys do not
// overlap), each checked by the pipeline that declares it whatever the scene; they override the
// chosen way's quality settings for the parts that declare them.
#include "pipelines/auto_pipeline.hpp"
#include "pipelines/registry.hpp"
#include "protocol/json_reader.hpp"

namespace scatter {

const PipelineInfo& thickness_info();
const PipelineInfo& reference_info();

namespace {

// Whose settings auto takes, and the pipelines its ways use (the calibration table's).
const std::vector<std::string> kDelegates = {"thickness", "reference"};
const std::vector<std::string> kChoices = {"thickness", "single", "lbl", "psf", "reference"};

// By the delegates' own info (the registry is not built yet while auto's info is).
std::vector<SettingInfo> delegate_settings() {
  std::vector<SettingInfo> all;
  for (const PipelineInfo* d : {&thickness_info(), &reference_info()})
    for (SettingInfo s : d->settings) {
      s.doc = d->name + ": " + s.doc;
      all.push_back(std::move(s));
    }
  return all;
}

void validate(const Settings& settings) {
  for (const auto& [key, value] : settings) {
    bool known = false;
    for (const std::string& d : kDelegates)
      known = known || !AutoPipeline::settings_for(d, {{key, value}}).empty();
    if (!known)
      throw ValidationError(
          "settings." + key,
          "is not a setting of pipeline auto (it takes those of thickness and reference)");
  }
  for (const std::string& d : kDelegates)
    pipeline_info(d).validate(AutoPipeline::settings_for(d, settings));
}

}  // namespace

Settings AutoPipeline::settings_for(const std::string& delegate, const Settings& settings) {
  Settings out;
  for (const SettingInfo& s : pipeline_info(delegate).settings)
    if (auto it = settings.find(s.key); it != settings.end()) out.insert(*it);
  return out;
}

const PipelineInfo& auto_info() {
  static const PipelineInfo info{
      .name = "auto",
      .summary =
          "the fastest way expected to meet an error budget (quality.max_error, default 10 %): one "
          "pipeline, single plus multiple from two, or the reference; the plan says why",
      .method = "docs/pipelines/auto.md",
      .terms = {Terms::Single, Terms::Multiple, Terms::All},
      .default_terms = Terms::Single,
      .settings = delegate_settings(),
      .validate = &validate,
      .bake_stages = {},
      .qualities = {{"normal", {}}},
      .delegates = kChoices,
      .make = [](gpu::Gpu& gpu, BakeCache* cache) -> std::unique_ptr<Pipeline> {
        return std::make_unique<AutoPipeline>(gpu, cache);
      },
      .estimate = &AutoPipeline::estimate};
  return info;
}

const PipelineInfo& AutoPipeline::info() const {
  return auto_info();
}

}  // namespace scatter
