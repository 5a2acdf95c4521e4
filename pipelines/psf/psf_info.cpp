// `psf` in the registry: its settings table and description.
#include "pipelines/psf/psf_pipeline.hpp"
#include "pipelines/registry.hpp"

namespace scatter {

const SettingsTable<PsfSettings>& psf_settings() {
  static const SettingsTable<PsfSettings> table(
      "psf",
      {setting("model", &PsfSettings::model, 0, 1, kept("lights"),
               "the multiple term: 0 the paper's (Algorithm 2: the pyramid read at one path "
               "length per point); 1 orders (each scattering order spread and drifted by its "
               "flight on a coarse pyramid level, with its own phase)"),
       setting("level", &PsfSettings::level, -1, 4, kept("lights"),
               "model 1: the pyramid level the orders run on; -1 the coarsest whose voxel is at "
               "most a third of the first flight's spread"),
       one_of(setting("flights", &PsfSettings::flights, 1, 3, kept("lights"),
                      "model 1: Gaussians per flight, 1 or 3 (3 follow the exponential flight's "
                      "radial distribution)"),
              {1, 3}),
       setting("drift", &PsfSettings::drift, -1, 1, kept("lights"),
               "model 1: the share of each flight's mean displacement along the light that is "
               "applied; -1 the calibrated min(0.5, 2.5 (1 - g)) (docs/BENCHMARKS.md)"),
       setting("flux", &PsfSettings::flux, 0, 2, frame(),
               "model 1: the diffusive flux's P1 part towards the camera, 0 none, 1 with one "
               "flight's D = 1 / (3 c), 2 with diffusion's 1 / (3 c (1 - g))"),
       flag("conserve", &PsfSettings::conserve, kept("lights"),
            "model 1: scale each order's source so that its flight's collisions, weighted by "
            "the local extinction, take what stays inside the mesh (0: cap b at the albedo "
            "times the mean extinction instead)"),
       flag("tail", &PsfSettings::tail, kept("lights"),
            "model 1: sum the orders past a steady decay as a geometric series"),
       setting("step", &PsfSettings::step, 0.05, 4, frame(),
               "the view march's sub-step, in voxels"),
       setting("spacing", &PsfSettings::spacing, 0.1, 10, frame(),
               "pyramid lookups per projected blur width"),
       setting("shift", &PsfSettings::shift, 0, 100, frame(),
               "the width formula's shift in scattering events (the paper's 8)"),
       setting("atten", &PsfSettings::atten, 0, 2, frame(),
               "0: Algorithm 2's weight over the whole path; 1: extinction over the view segment; "
               "2: absorption "
               "only over the view segment (equation 11's action)"),
       setting("thin", &PsfSettings::thin, 0, 10, frame(),
               "scattering optical thickness below which the multiple term is skipped"),
       flag("rebuild", &PsfSettings::rebuild, frame(),
            "1: drop the kept light volumes first, as if every light had moved (benchmarks)")});
  return table;
}

PsfSettings PsfSettings::read(const Settings& settings) {
  return psf_settings().read(settings);
}

const PipelineInfo& psf_info() {
  static const PipelineInfo info = describe<PsfPipeline>(
      psf_settings(),
      {.summary = "single and multiple scattering by a point-spread function: a light volume and "
                  "its Gaussian "
                  "pyramid per light, kept across camera moves, and a view march, OpenCL",
       .method = "docs/pipelines/psf.md (papers/psf-multiple-scattering.md)",
       .terms = {Terms::Single, Terms::Multiple, Terms::All},
       .default_terms = Terms::All,
       .qualities = {{"draft", {{"step", 2}}}, {"normal", {}}, {"high", {{"step", 0.5}}}}});
  return info;
}

const PipelineInfo& PsfPipeline::info() const {
  return psf_info();
}

}  // namespace scatter
