// The `psf` pipeline: Premoze et al.'s multiple scattering by a point-spread function
// (papers/psf-multiple-scattering.md), with single scattering by fine ray marching of the same
// light volume. Per light (kept while the light and the medium stay the same): the light volume
// (unscattered light, scattering events and optical depth towards the light, per voxel) and the
// Gaussian pyramid of its scattered source (pipelines/psf/light_pyramid.hpp). Per frame: one
// march per light (kernels/psf/march.cl). A camera-only change reuses every pyramid; a moved
// light rebuilds its own only. Refraction and Fresnel are neglected (straight rays).
//
// Settings: the table in pipelines/psf/psf_info.cpp (`scatterd pipelines`, docs/pipelines/psf.md).
// model 1 (`orders`, pipelines/psf/orders.hpp) is the default; model 0 is the paper's march
// (Algorithm 2, with atten 2, absorption only over the view segment, as its default); figures in
// docs/BENCHMARKS.md.
#pragma once

#include <array>
#include <map>
#include <memory>

#include "pipelines/common/cl_scene.hpp"
#include "pipelines/cost.hpp"
#include "pipelines/pipeline.hpp"
#include "pipelines/psf/light_pyramid.hpp"
#include "pipelines/psf/orders.hpp"
#include "pipelines/psf/psf_model.hpp"

namespace scatter {

struct PsfSettings {
  int model = 1;  // 0: the paper's (Algorithm 2); 1: orders
  int level = -1;
  int flights = 3;
  bool tail = true;
  bool conserve = true;
  int flux = 0;
  double drift = -1;  // -1: psf::calibrated_drift(g)
  double step = 1;
  double spacing = 1;
  double shift = 8;
  int atten = 2;
  double thin = 0.05;
  bool rebuild = false;
  static PsfSettings read(const Settings& settings);
};

class PsfPipeline : public Pipeline {
 public:
  // What render() (bake: bake()) of `scene` will cost, without a GPU or an instance
  // (pipelines/cost.hpp); throws ValidationError for settings render() would reject.
  static CostEstimate estimate(const Scene& scene, const RenderRequest& request, bool bake);
  explicit PsfPipeline(gpu::Gpu& gpu) : gpu_(gpu) {}
  const PipelineInfo& info() const override;
  Plan plan(const Scene& scene, const RenderRequest& request) override;
  RenderResult render(const Scene& scene, const RenderRequest& request) override;

  // For tests: light volumes built so far (each build of one light counts one).
  int light_builds() const { return light_builds_; }
  // The largest scattering optical thickness across the grid (max sigma_s x longest side).
  double scattering_thickness() const { return thickness_; }

 private:
  struct Medium {
    std::string fingerprint;
    std::shared_ptr<const DensityField> density;  // keeps the fingerprinted address taken
    std::unique_ptr<ClMedium> cl;
    cl::Buffer occupancy;  // float per voxel: its share inside the mesh (model 1's conserve)
    std::map<std::string, psf::LightVolume> lights;  // by the light's packed parameters
    std::map<std::string, psf::Orders> orders;       // model 1's, by the same keys
    std::array<double, 3> mean_sigma_t{};            // c over the medium's voxels
    psf::PmsTable pms;
    cl::Buffer pms_buf;
  };
  void prepare(const Scene& scene);  // voxelizes and uploads unless the medium is the one held
  // Throws ValidationError (field scene.voxels) when the volumes would not fit the device's memory.
  void check_memory(const Scene& scene);
  std::vector<std::string> light_keys(const Scene& scene) const;
  // The stages for this scene and request given whether the medium is held and its scattering
  // thickness (`note` says how that was known).
  Plan make_plan(const Scene& scene, const RenderRequest& request, const PsfSettings& s, bool held,
                 double thickness, const std::string& note) const;
  // Model 1's parameters for the held medium, and whether the orders held for light `key` were
  // built with them (else render() builds them again).
  psf::OrderParams order_params(const Scene& scene, const PsfSettings& s) const;
  bool orders_held(const std::string& key, const psf::OrderParams& op) const;

  gpu::Gpu& gpu_;
  Medium medium_;
  double thickness_ = 0;
  int light_builds_ = 0;
};

}  // namespace scatter
