// The light's second scattering computed exactly, so that the lattice carries only the third
// and later events (setting `second`, kernels/lbl/second.cl). The 6-direction lattice sends a
// node's emission along the axes: next to a surface 4 of its 6 directions run along it, so the
// light of the first scatterings, which sit within a mean free path of the lit face, stays near
// that face and leaves through it too often (a slab lit at grazing incidence transmitted 36 %
// too little). A gather over 32 directions from every voxel through the delta-Eddington scaled
// medium takes the march's (scaled) deposit to where it scatters next; that is the lattice's
// source, and the view sees it with the lattice's irradiance as the multiple term's emission.
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "gpu/cl_context.hpp"
#include "pipelines/lbl/volume.hpp"

namespace scatter::lbl {

// Directions of the gather (a Fibonacci spiral, as the escape correction's).
constexpr int kSecondDirections = 32;
// The grid next_order() gathers on: this many halvings of the voxels' resolution.
constexpr int kOrderLevel = 1;
// Gathers per launch (a cancel point between launches).
constexpr size_t kSecondChunk = 65536;

// The gather's buffers for one material: sigma_t' at full and half resolution and, with
// `stride` > 1, the escape correction's sampling (pipelines/lbl/escape.hpp: every stride-th
// voxel, the others inside one medium interpolated trilinearly, those next to a surface, a
// blocker or a density step computed themselves); `far` > 0: past `far` voxel widths a ray
// crosses the half-resolution grid.
class SecondScatter {
 public:
  SecondScatter(gpu::ClContext& cl, const Volume& v, const ClVolume& device, double g,
                int stride = 1, double far = 0, int directions = kSecondDirections,
                int order_level = kOrderLevel);
  // Q2 per voxel and channel into `out` (3 floats per voxel, the source's units: power per voxel
  // per lattice step): sigma_s' V times the fluence of the light `source` emits isotropically;
  // into `direction` (3 floats per voxel) that light's mean direction of travel m (its net flux
  // over its fluence, channels summed, |m| <= 1; 0 where none arrives).
  // The gathers run in launches of about kSecondChunk voxels; with `progress`, each launch is
  // waited for and progress(f) called after it, f the fraction of launches done (it may throw to
  // stop: a cancelled render).
  // Otherwise enqueued, not waited for.
  void run(const cl::Buffer& source, cl::Buffer& out, cl::Buffer& direction,
           const std::function<void(double)>& progress = {});
  // The next order from `source` (setting `gathers`; source as run()'s, Q_k): Q_k+1 into `out`
  // and added into `sum` (3 floats per voxel each; `out` may be `source`, `sum` may be `source`
  // but not `out`). On the half-resolution grid: the source averaged over each cell of 2 x 2 x 2
  // voxels (kOrderLevel halvings: 2 x 2 x 2), phi V gathered at the cells' centres (the cells
  // within one of a scattering voxel's) over the same directions through the cells' mean
  // sigma_t', trilinear back to the voxels.
  // Enqueued, not waited for.
  void next_order(const cl::Buffer& source, cl::Buffer& out, cl::Buffer& sum);
  // The voxels whose gather runs (samples and voxels computed themselves).
  size_t gathers() const { return gathers_; }
  // The cells next_order() gathers at.
  size_t order_gathers() const { return level_listed_; }

 private:
  gpu::ClContext& cl_;
  ClVolume v_;
  double g_, far_;
  int stride_, directions_, order_level_;
  std::array<int, 3> n_{};
  size_t samples_count_ = 0, gathers_ = 0, count_ = 0, coarse_count_ = 0, level_listed_ = 0;
  cl::Buffer sigma_t_, coarse_t_, coarse_source_, dirs_, list_, mode_, samples_, msamples_;
  // next_order()'s: the voxels' sigma_s, its grid's sigma_t', cells listed and phi V, and the
  // source at each level.
  cl::Buffer sigma_s_, level_t_, level_list_, level_phi_;
  std::vector<cl::Buffer> level_sources_;
  std::array<int, 3> level_n_{};
};

}  // namespace scatter::lbl
