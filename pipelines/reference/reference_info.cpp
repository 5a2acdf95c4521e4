// `reference` in the registry: its settings table and description.
#include "pipelines/reference/reference_pipeline.hpp"
#include "pipelines/registry.hpp"

namespace scatter {

const SettingsTable<ReferenceSettings>& reference_settings() {
  static const SettingsTable<ReferenceSettings> table(
      "reference", {setting("spp", &ReferenceSettings::spp, 3, 1 << 20, frame(),
                            "samples per pixel (each carries the three colour channels)"),
                    setting("step", &ReferenceSettings::step, 1e-3, 4, frame(),
                            "the single-scatter marcher's sub-step, in voxels"),
                    setting("seed", &ReferenceSettings::seed, 0, 1 << 30, frame(),
                            "random seed of the Monte Carlo estimates"),
                    setting("max_depth", &ReferenceSettings::max_depth, 1, 1 << 20, frame(),
                            "scattering events per path, at most"),
                    flag("mc", &ReferenceSettings::mc, frame(),
                         "1: the single term by Monte Carlo (next-event estimation at the first "
                         "vertex) instead of marching"),
                    flag("voxel_boundary", &ReferenceSettings::voxel_boundary, frame(),
                         "1: with ior 1, the voxelized medium alone (each voxel's mean over its "
                         "whole volume: the staircase other pipelines see at the same grid) "
                         "instead of the density grid bounded by the mesh"),
                    setting("cells", &ReferenceSettings::cells, 0, 2, frame(),
                            "the path tracer's mesh queries (the same hits): 0 traverse the BVH, "
                            "1 walk per-voxel triangle lists with the voxel DDA, 2 the lists "
                            "where they are short on a large mesh (uses_cell_lists)"),
                    flag("exit_maps", &ReferenceSettings::exit_maps, frame(),
                         "1: on a convex mesh, shadow rays find their exit among the "
                         "triangles of one cell of a map of the mesh's light-facing triangles "
                         "(over the plane normal to a directional light; in perspective from a "
                         "point or spot light the whole mesh lies in front of), the same hits; "
                         "0: by the mesh queries `cells` chooses"),
                    flag("homogeneous", &ReferenceSettings::homogeneous, frame(),
                         "1: where the mesh bounds a medium of one coefficient (a constant "
                         "density), the path tracer's flights and optical depths are taken "
                         "without walking the bricks (the same values); 0: walked as any "
                         "medium's"),
                    setting("batch", &ReferenceSettings::batch, 0, 1 << 12, frame(),
                            "the path tracer's samples per stratified batch: within a batch "
                            "each flight's first collision and each scattering direction are "
                            "stratified (padded Owen-scrambled Sobol), batches are independent "
                            "and the standard error comes from their spread; 1: independent "
                            "samples; 0: the largest power of two up to 16 that leaves 32 "
                            "batches"),
                    setting("max_seconds", &ReferenceSettings::max_seconds, 0, 86400, frame(),
                            "the path tracer's time for its samples (the trace stage), in "
                            "seconds: no pass starts once not even half a sample fits in what "
                            "is left, never before three samples; the image is the mean of the "
                            "samples drawn, its standard error theirs; 0: no limit")});
  return table;
}

ReferenceSettings ReferenceSettings::read(const Settings& settings) {
  return reference_settings().read(settings);
}

const PipelineInfo& reference_info() {
  static const PipelineInfo info = describe<ReferencePipeline>(
      reference_settings(),
      {.summary = "ground truth in OpenCL: a deterministic single-scatter marcher and a volumetric "
                  "path tracer "
                  "for all orders; Fresnel and refraction at the mesh when ior != 1",
       .method = "docs/pipelines/reference.md",
       .terms = {Terms::Single, Terms::Multiple, Terms::All},
       // The marcher's single term is the interactive one; all orders take the path tracer 16-170 s
       // a frame on a 2-core CPU.
       .default_terms = Terms::Single,
       .qualities = {{"draft", {{"step", 0.5}}}, {"normal", {}}, {"high", {{"step", 0.125}}}}});
  return info;
}

const PipelineInfo& ReferencePipeline::info() const {
  return reference_info();
}

}  // namespace scatter
