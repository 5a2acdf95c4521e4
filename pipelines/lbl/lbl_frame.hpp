// What an lbl frame runs and keeps (pipelines/lbl/lbl_pipeline.cpp): the keys of what is loaded,
// the state kept between frames, the decision which stages run, and the plan that says why.
#pragma once

#include <memory>
#include <string>

#include "pipelines/lbl/lattice.hpp"
#include "pipelines/lbl/lbl_pipeline.hpp"
#include "pipelines/lbl/second.hpp"
#include "pipelines/lbl/volume.hpp"

namespace scatter::lbl {

// What the material volume and the lattice depend on: the asset, its medium, the grid, and the
// settings that shape them (not the lights, not the camera).
std::string material_key(const Scene& scene, const LblSettings& s);
// The lights and the settings kept with the march's deposit.
std::string light_key(const Scene& scene, const LblSettings& s);
// The settings kept with a converged diffusion.
std::string diffusion_key(const LblSettings& s);

// The lattice's state is the largest buffer: refuse, before voxelizing, a grid whose state the
// device cannot allocate (the grid's sides estimated from the mesh's bounds).
void check_lattice_size(const Scene& scene, const LblSettings& s, int margin, uint64_t max_alloc);

struct State {
  std::string material, lights, diffusion;      // keys of what is loaded
  std::shared_ptr<const DensityField> density;  // keeps the keyed address alive
  Volume volume;
  ClVolume device;
  std::unique_ptr<Lattice> lattice;
  cl::Buffer deposit;  // single scattering of the light rays (the single term)
  cl::Buffer source;   // the lattice's source: the deposit, or with g != 0 the scaled beam's
  cl::Buffer flow;     // with g != 0: the deposit's direction summed over channels (3 per voxel,
                       // the view's phase), then the forward-scattered light's scattering (3)
  int lobes = 1;       // light_lobes(): with more than 1, each light's deposit and flow, one
  cl::Buffer lobe_deposit, lobe_flow;  // after the other (what the view reads, not deposit, flow)
  cl::Buffer lattice_flux;    // flux_phase: the lattice's light direction m (3 per voxel), made
                              // when first used
  bool flux_current = false;  // lattice_flux is the last diffusion's
  std::unique_ptr<SecondScatter> gather;  // setting second: its gather, made when first used
  cl::Buffer second;      // setting second: the light's second scattering (3 per voxel), with
                          // gathers > 1 the orders 2 to gathers + 1 summed (what the view adds)
  cl::Buffer second_dir;  // and the mean direction the second's light travels in (3 per voxel)
  cl::Buffer last;        // gathers > 1: the last gathered order (the lattice's source)
  bool second_current = false;  // second, second_dir and last are the gathers of the loaded
  int second_gathers = 0;       // deposit, by this many gathers
  double max_sigma_s = 0;
  // The lattice has converged for the loaded deposit and settings; with_second: from the second
  // scattering (it carried the third and later events; the view adds second's light). Both
  // are cleared when a diffusion starts and set when it finishes: a cancelled one leaves neither.
  bool diffused = false, with_second = false;
};

// The view scatters the lattice's light with the phase's first moment about its direction
// (setting flux_phase; the 6-direction lattice's flux only).
bool uses_flux_phase(const Scene& scene, const LblSettings& s);
// The view sees the scaled problem through sigma_t' with its first scattering by the real phase
// (setting tms; g > 0, not with scaled_view).
bool uses_tms(const Scene& scene, const LblSettings& s);
// The lattice starts from the light's exactly computed second scattering (setting second; the
// 6-direction lattice, not interleaved with the march).
bool uses_second(const LblSettings& s);
// How many deposits the march keeps apart (setting lobes), each with its own phase lobe about
// its light's mean direction: when g != 0, there are 2 or more lights and the march is not
// interleaved, the least of the lights, `lobes` and what fits kMaxLobeBytes (36 B a node each,
// on the grid the cost estimate takes); 1 (one deposit, one lobe about all the lights' mean
// direction) where that is under 2.
int light_lobes(const Scene& scene, const LblSettings& s);
// The lights of each of `lobes` deposits: each light alone when there are as many lobes as
// lights, else grouped by direction (seen from the mesh's centre; directional lights by theirs),
// spherical k-means from the farthest-apart lights, deterministic. Every light in exactly one
// group, none empty; groups in the order of their first light.
std::vector<std::vector<int>> light_groups(const Scene& scene, int lobes);

// Which stages a frame runs, from the scene, the request and what the last frame left.
struct Decision {
  bool material = true, march = true, diffuse = true, multiple = true, single = true;
  bool tiny = false, bend = false;
  bool gather = false;  // the diffusion gathers the second scattering anew (not kept)
  double bound = 1;
  std::string bound_note;
};
Decision decide(const State* state, const Scene& scene, const RenderRequest& request,
                const LblSettings& s);
// The diffuse stage's entry of the plan.
StagePlan diffuse_stage(const Decision& d, const LblSettings& s);
Plan make_plan(const Scene& scene, Terms terms, const LblSettings& s, const Decision& d);

}  // namespace scatter::lbl
