// `thickness` in the registry: its settings table and description.
#include "pipelines/registry.hpp"
#include "pipelines/thickness/thickness_pipeline.hpp"

namespace scatter {

const SettingsTable<ThicknessSettings>& thickness_settings() {
  static const SettingsTable<ThicknessSettings> table(
      "thickness",
      {setting("steps", &ThicknessSettings::steps, 1, 1024, frame(), "pieces per view segment"),
       setting("shadow_size", &ThicknessSettings::shadow_size, 64, 8192, frame(),
               "shadow-map side in texels")});
  return table;
}

ThicknessSettings ThicknessSettings::read(const Settings& settings) {
  return thickness_settings().read(settings);
}

const PipelineInfo& thickness_info() {
  static const PipelineInfo info = describe<ThicknessPipeline>(
      thickness_settings(),
      {.summary = "single scattering in a homogeneous medium from a shadow map per light and depth "
                  "peeling, "
                  "integrated analytically; no bake, OpenGL",
       .method = "docs/pipelines/thickness.md (papers/thickness-single-scattering-blog.md)",
       .terms = {Terms::Single},
       .default_terms = Terms::Single,
       .qualities = {{"draft", {{"steps", 12}, {"shadow_size", 512}}},
                     {"normal", {}},
                     {"high", {{"steps", 96}, {"shadow_size", 2048}}}}});
  return info;
}

const PipelineInfo& ThicknessPipeline::info() const {
  return thickness_info();
}

}  // namespace scatter
