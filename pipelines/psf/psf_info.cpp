// `psf` in the registry: its settings table and description.
#include "pipelines/psf/psf_pipeline.hpp"
#include "pipelines/registry.hpp"

namespace scatter {

const SettingsTable<PsfSettings>& psf_settings() {
  static const SettingsTable<PsfSettings> table(
      "psf",
      {setting("step", &PsfSettings::step, 0.05, 4, frame(),
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
