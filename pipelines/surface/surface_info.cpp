// `surface` in the registry: its settings table and description.
#include "pipelines/registry.hpp"
#include "pipelines/surface/surface_pipeline.hpp"

namespace scatter {

const SettingsTable<SurfaceSettings>& surface_settings() {
  static const SettingsTable<SurfaceSettings> table(
      "surface", {flag("shadows", &SurfaceSettings::shadows, frame(),
                       "1: a distance map per light; a facet is lit only where no surface lies "
                       "nearer to the light"),
                  setting("shadow_size", &SurfaceSettings::shadow_size, 64, 8192, frame(),
                          "shadow-map side in texels")});
  return table;
}

SurfaceSettings SurfaceSettings::read(const Settings& settings) {
  return surface_settings().read(settings);
}

const PipelineInfo& surface_info() {
  static const PipelineInfo info = describe<SurfacePipeline>(
      surface_settings(),
      {.summary = "the mesh alone: energy-normalised Blinn-Phong under the scene's lights, OpenGL",
       .method = "docs/pipelines/surface.md",
       .terms = {Terms::Surface},
       .default_terms = Terms::Surface,
       .qualities = {{"normal", {}}}});
  return info;
}

const PipelineInfo& SurfacePipeline::info() const {
  return surface_info();
}

}  // namespace scatter
