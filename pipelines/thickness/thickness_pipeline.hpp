// `thickness`: single scattering in a homogeneous medium from a shadow map per light and depth
// peeling (papers/thickness-single-scattering-blog.md). No bake: the front and back surfaces come
// from two raster passes, the light's path inside the medium from its shadow map, and the
// in-scattering integral along the view segment is summed over `steps` pieces with the view
// transmittance integrated exactly in each.
//
// Settings: the table in pipelines/thickness/thickness_info.cpp (`scatterd pipelines`,
// docs/pipelines/thickness.md). Approximations (as the blog): only the first segment inside the
// object is integrated, the light enters at the surface nearest to it, and refraction and Fresnel
// at the boundary are neglected.
//
// Kept between frames (a live view's camera-only changes cost only the depth peel and the
// integral): the mesh's GL buffers, and the shadow maps of the last kKeptShadowSets light sets
// (by mesh, lights and shadow_size: a moving view's draft maps and the still view's both stay).
#pragma once

#include <list>
#include <memory>
#include <string>
#include <vector>

#include "gpu/gl_objects.hpp"
#include "pipelines/common/raster.hpp"
#include "pipelines/cost.hpp"
#include "pipelines/pipeline.hpp"

namespace scatter {

struct ThicknessSettings {
  int steps = 32;
  int shadow_size = 1024;
  static ThicknessSettings read(const Settings& settings);
};

class ThicknessPipeline : public Pipeline {
 public:
  // What render() (bake: bake()) of `scene` will cost, without a GPU or an instance
  // (pipelines/cost.hpp); throws ValidationError for settings render() would reject.
  static CostEstimate estimate(const Scene& scene, const RenderRequest& request, bool bake);
  explicit ThicknessPipeline(gpu::Gpu& gpu) : gpu_(gpu) {}
  const PipelineInfo& info() const override;
  Plan plan(const Scene& scene, const RenderRequest& request) override;
  RenderResult render(const Scene& scene, const RenderRequest& request) override;

 private:
  static constexpr size_t kKeptShadowSets = 2;
  struct Shadows {
    std::string key;  // shadows_key()
    std::vector<std::unique_ptr<RenderTarget>> maps;
    std::vector<Mat4> light_matrices;
  };
  // The stages for this scene, terms and settings.
  Plan describe(const Scene& scene, Terms terms, const ThicknessSettings& s) const;
  static std::string shadows_key(const Scene& scene, const ThicknessSettings& s);
  const Shadows* kept_shadows(const std::string& key) const;
  // The shadow maps for the scene's lights: kept ones, else drawn (and kept).
  const Shadows& shadows(const Scene& scene, const ThicknessSettings& s, const MeshBuffers& mesh);

  gpu::Gpu& gpu_;
  gpu::GlObject distance_program_, integrate_program_, empty_vao_;
  KeptMesh mesh_;
  std::list<Shadows> kept_;  // most recently used first
};

}  // namespace scatter
