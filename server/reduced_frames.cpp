#include "server/reduced_frames.hpp"

#include <algorithm>
#include <cmath>

#include "pipelines/registry.hpp"

namespace scatter::server {

Settings with_draft(const std::string& pipeline, Settings s) {
  const PipelineInfo& info = pipeline_info(pipeline);
  Settings draft = info.moving;
  if (draft.empty())
    for (const Quality& q : info.qualities)
      if (q.name == "draft") draft = q.settings;
  for (const auto& [key, value] : draft)
    for (const SettingInfo& setting : info.settings)
      if (setting.key == key && setting.shapes.what == Shapes::What::Frame) s[key] = value;
  return s;
}

Settings ReducedFrames::settings(const std::string& pipeline, const Settings& settings) {
  return choice(pipeline).draft ? with_draft(pipeline, settings) : settings;
}

void ReducedFrames::measured(const std::string& pipeline, double render_ms) {
  if (render_ms <= 0) return;
  Choice& c = chosen_[pipeline];
  double wanted = c.scale * std::sqrt(kFrameBudgetMs / render_ms);
  if (wanted < kMinScale) c.draft = true;
  c.scale = std::clamp(wanted, kMinScale, kMaxScale);
}

}  // namespace scatter::server
