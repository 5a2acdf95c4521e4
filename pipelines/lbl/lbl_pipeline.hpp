// `lbl`: Bernabei et al.'s parallel architecture for scattering and refraction
// (papers/lbl-scattering-refraction.md), in OpenCL.
//
//   volume   material volume from the voxel grid: sigma_s, sigma_t, n (ior blended by occupancy,
//            Gaussian-smoothed) and grad n (pipelines/lbl/volume)
//   march    light rays from every light deposit the power they scatter per voxel, bending by
//            the ray equation where n varies (kernels/lbl/march.cl)
//   second   the light's second scattering gathered exactly from the deposit (setting second,
//            pipelines/lbl/second, kernels/lbl/second.cl), and with setting gathers the next
//            orders from it on the half-resolution grid
//   diffuse  lattice-Boltzmann diffusion of it (or of the deposit; global or in blocks), to
//            convergence, warm-started from the last state (pipelines/lbl/lattice,
//            kernels/lbl/lattice.cl)
//   view     per pixel, the eye ray (refracted where n varies) gathers the deposit (single term)
//            and the lattice's scattered power (multiple term) (kernels/lbl/view.cl)
//
// The volume, the deposit and the lattice's state are kept between frames: a camera-only change
// runs only the view pass; a light change re-marches and warm-starts the lattice. What is kept,
// and which stages a frame runs: pipelines/lbl/lbl_frame.
//
// Settings: the table in pipelines/lbl/lbl_info.cpp (`scatterd pipelines`, docs/pipelines/lbl.md).
#pragma once

#include <memory>
#include <optional>

#include "pipelines/cost.hpp"
#include "pipelines/lbl/lattice.hpp"
#include "pipelines/lbl/volume.hpp"
#include "pipelines/pipeline.hpp"
#include "pipelines/settings_table.hpp"
#include "pipelines/surface/surface_pipeline.hpp"

namespace scatter {
namespace lbl {
struct State;
}

struct LblSettings {
  double rays = 2;
  double step = 0.5;
  double smooth = 1;
  double cutoff = 1e-4;
  int lobes = 16;
  bool blocked = false;
  int block = 4;
  int inner = 1;
  int directions = 6;
  bool escape = true;
  int escape_stride = 2;
  double escape_far = 4;
  bool scaled_view = false;
  bool tms = true;
  bool flux_phase = true;
  bool second = true;
  bool second_phase = false;
  int gathers = 3;
  double tolerance = 1e-3;
  int max_steps = 20000;
  int check_every = 16;
  bool warm = true;
  double skip_multiple = 1e-3;
  bool measure = false;
  int interleave = 0;
  static LblSettings read(const Settings& settings);
};
// The settings table (pipelines/lbl/lbl_info.cpp).
const SettingsTable<LblSettings>& lbl_settings();

class LblPipeline : public Pipeline {
 public:
  // What render() (bake: bake()) of `scene` will cost, without a GPU or an instance
  // (pipelines/cost.hpp); throws ValidationError for settings render() would reject.
  static CostEstimate estimate(const Scene& scene, const RenderRequest& request, bool bake);
  explicit LblPipeline(gpu::Gpu& gpu);
  ~LblPipeline() override;
  const PipelineInfo& info() const override;
  Plan plan(const Scene& scene, const RenderRequest& request) override;
  RenderResult render(const Scene& scene, const RenderRequest& request) override;
  // True when the frame would run only the view pass (a camera-only change).
  bool keeps(const Scene& scene, const RenderRequest& request) const override;
  // Lattice steps the last diffusion took (0 when the last frame did not diffuse).
  int last_diffusion_steps() const { return last_steps_; }

 private:
  gpu::Gpu& gpu_;
  std::unique_ptr<lbl::State> state_;         // what the last frame left: volume, deposit, lattice
  std::unique_ptr<SurfacePipeline> surface_;  // the surface term (shadowed Blinn-Phong)
  RenderRequest surface_request(const RenderRequest& request);
  int last_steps_ = 0;
};

}  // namespace scatter
