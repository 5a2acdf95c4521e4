// `surface`: the mesh alone, rasterised with energy-normalised Blinn-Phong under the scene's
// lights through EGL. The smallest end-to-end path; the raster pieces it draws with
// (pipelines/common/raster) serve the other pipelines too.
// Settings: the table in pipelines/surface/surface_info.cpp (`scatterd pipelines`,
// docs/pipelines/surface.md).
#pragma once

#include "gpu/gl_objects.hpp"
#include "pipelines/cost.hpp"
#include "pipelines/pipeline.hpp"

namespace scatter {

struct SurfaceSettings {
  bool shadows = false;
  int shadow_size = 1024;
  static SurfaceSettings read(const Settings& settings);
};

class SurfacePipeline : public Pipeline {
 public:
  // What render() (bake: bake()) of `scene` will cost, without a GPU or an instance
  // (pipelines/cost.hpp); throws ValidationError for settings render() would reject.
  static CostEstimate estimate(const Scene& scene, const RenderRequest& request, bool bake);
  explicit SurfacePipeline(gpu::Gpu& gpu) : gpu_(gpu) {}
  const PipelineInfo& info() const override;
  Plan plan(const Scene& scene, const RenderRequest& request) override;
  RenderResult render(const Scene& scene, const RenderRequest& request) override;

 private:
  // The stages for this scene, terms and settings.
  Plan describe(const Scene& scene, Terms terms, const SurfaceSettings& s) const;
  gpu::Gpu& gpu_;
  gpu::GlObject program_, distance_program_;
};

}  // namespace scatter
