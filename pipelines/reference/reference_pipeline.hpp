// `reference`: ground truth in OpenCL: the medium is the density grid (each voxel holds constant
// sigma_s, sigma_a: their mean over the voxel's part inside the mesh) bounded by the mesh exactly
// (a BVH; voxel_boundary=1: the voxelized medium alone, the staircase the other pipelines see at
// the same grid). With ior != 1 the mesh is also a dielectric boundary (kernels/reference/
// boundary.cl): view rays and paths reflect and refract with Fresnel's weights; shadow rays to
// the (point-like) lights go straight, weighted by the Fresnel transmittance of each crossing.
//
//   single term, default    deterministic ray marcher (kernels/reference/single_march.cl)
//   single term, mc=1       Monte Carlo, NEE at the first vertex only
//   multiple, all           Monte Carlo path tracer (kernels/reference/path.cl)
//
// Settings: the table in pipelines/reference/reference_info.cpp (`scatterd pipelines`,
// docs/pipelines/reference.md).
#pragma once

#include "pipelines/cost.hpp"
#include "pipelines/pipeline.hpp"
#include "pipelines/reference/cell_triangles.hpp"

namespace scatter {

struct ReferenceSettings {
  int spp = 64;
  double step = 0.25;
  uint32_t seed = 1;
  int max_depth = 1024;
  bool mc = false;
  bool voxel_boundary = false;
  int cells = 2;  // the mesh queries: 0 the BVH, 1 the voxels' lists, 2 whichever suits the mesh
  bool exit_maps = true;    // shadow rays leave a convex mesh through maps of its light-facing side
  bool homogeneous = true;  // a constant medium inside the mesh is tracked without walks
  int batch = 0;  // samples per stratified batch (kernels/reference/path.cl); 0: batch_for(spp)
  double max_seconds = 0;  // > 0: the path tracer stops sampling once its passes took this long
  static ReferenceSettings read(const Settings& settings);
  // The single term by the deterministic marcher (not mc).
  bool marches(Terms terms) const { return terms == Terms::Single && !mc; }
  // Whether a render of a mesh of `triangles` builds the voxels' triangle lists (they are then
  // used where they pay: uses_cell_lists).
  bool builds_cell_lists(size_t triangles, Terms terms) const {
    return (cells == 1 || (cells == 2 && triangles >= kCellListsMinTriangles)) && !marches(terms);
  }
};

// The samples per stratified batch when `batch` is 0: the largest power of two up to 16 that
// leaves at least 32 batches in `spp` samples (1 below 64), so that each pixel's standard error
// rests on 31 or more degrees of freedom.
int batch_for(int spp);

class ReferencePipeline : public Pipeline {
 public:
  // What render() (bake: bake()) of `scene` will cost, without a GPU or an instance
  // (pipelines/cost.hpp); throws ValidationError for settings render() would reject.
  static CostEstimate estimate(const Scene& scene, const RenderRequest& request, bool bake);
  explicit ReferencePipeline(gpu::Gpu& gpu) : gpu_(gpu) {}
  const PipelineInfo& info() const override;
  Plan plan(const Scene& scene, const RenderRequest& request) override;
  RenderResult render(const Scene& scene, const RenderRequest& request) override;

 private:
  // The stages for this scene, terms and settings.
  Plan describe(const Scene& scene, Terms terms, const ReferenceSettings& s) const;
  gpu::Gpu& gpu_;
};

}  // namespace scatter
