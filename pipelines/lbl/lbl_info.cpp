// `lbl` in the registry: its settings table and description.
#include "pipelines/lbl/lbl_limits.hpp"
#include "pipelines/lbl/lbl_pipeline.hpp"
#include "pipelines/registry.hpp"
#include "protocol/json_reader.hpp"

namespace scatter {

const SettingsTable<LblSettings>& lbl_settings() {
  using S = LblSettings;
  static const SettingsTable<LblSettings> table(
      "lbl",
      {setting("rays", &S::rays, 0.25, 8, kept("lights"), "light rays per voxel width"),
       setting("step", &S::step, 0.05, 2, kept("lights"), "the Eikonal step, in voxels"),
       setting("smooth", &S::smooth, 0, 4, kept("material"),
               "Gaussian on the refractive index, in voxels"),
       setting("cutoff", &S::cutoff, 0, 0.5, kept("lights"),
               "a light ray stops under this fraction of its power"),
       setting("lobes", &S::lobes, 1, lbl::kMaxLobes, kept("lights"),
               "with g != 0 and several lights, up to this many lights each keep their own "
               "deposit and direction, so that the single term (and the forward-scattered light) "
               "takes each light's phase lobe (36 B a node a lobe); more lights than that are "
               "grouped by direction into that many lobes, each about its group's mean "
               "direction; 1: one lobe about all the lights' mean direction"),
       flag("blocked", &S::blocked, kept("material"),
            "1: the paper's blocks with interface buffers; 0: the global lattice (faster on a CPU "
            "device)"),
       setting("block", &S::block, 1, 8, kept("material"), "the blocks' side b, in nodes"),
       setting("inner", &S::inner, 1, 16, kept("material"), "lattice steps per block launch"),
       one_of(setting("directions", &S::directions, 6, 18, kept("material"),
                      "6 (the paper's lattice) or 18 (Geist et al.'s, global form only)"),
              {6, 18}),
       flag("escape", &S::escape, kept("material"),
            "1: scale each node's emission by the escape correction, a Marshak-type boundary "
            "(6 directions; docs/pipelines/lbl.md); 0: the open lattice alone"),
       setting("escape_stride", &S::escape_stride, 1, 4, kept("material"),
               "the escape correction's exact part at one voxel in n per axis, log-trilinear "
               "between inside one medium, at the voxel itself next to a surface, blocker or "
               "density step (1: at every voxel); the second scattering's gather samples the same "
               "way"),
       setting("escape_far", &S::escape_far, 0, 64, kept("material"),
               "with escape_stride > 1: its rays cross the voxels for this many voxel widths, "
               "then a grid of half the resolution (0: the voxels all the way); the second "
               "scattering's gather's too"),
       flag("scaled_view", &S::scaled_view, frame(),
            "1: the view pass gathers the multiple term through the delta-Eddington scaled medium "
            "(sigma_s', sigma_t'), as the lattice carries it; 0: through the real one"),
       flag("tms", &S::tms, frame(),
            "with g > 0 and scaled_view 0, 1: the view sees the delta-Eddington scaled problem "
            "the lattice solves through sigma_t' = sigma_t - g sigma_s, its first scattering by "
            "the real phase (the TMS correction): the lattice's and the second scattering's light "
            "emitted by sigma_s (1 - g), the scaled beam's by sigma_s HG, the single term's own "
            "light's gain through sigma_t' counted in the multiple term; 0: the multiple term "
            "emitted by sigma_s through the real sigma_t"),
       flag(
           "flux_phase", &S::flux_phase, frame(),
           "1: with g != 0 the lattice's light is scattered towards the eye by 1 + 3 g m . w, m "
           "its net flux over its total (6 directions, |m| <= 1/3; with second and second_phase 0, "
           "the second scattering's light by the same m, an approximation); 0: isotropically"),
       flag("second", &S::second, kept("diffusion"),
            "1: the light's second scattering computed exactly (a gather over 32 directions "
            "through the scaled medium, at escape_stride and escape_far), the lattice carrying "
            "the third and later events (6 directions, not with interleave); 0: the lattice from "
            "the first scattering's light"),
       flag("second_phase", &S::second_phase, frame(),
            "with second and g != 0, 1: the second scattering's light is scattered towards the "
            "eye by HG(g |m|) about m, the mean direction the gather found it arriving in (the "
            "single term's model); 0: isotropically"),
       setting("gathers", &S::gathers, 1, lbl::kMaxGathers, kept("diffusion"),
               "with second, the scattering orders 2 to n + 1 computed exactly: the second by the "
               "gather, each later one gathered from the last over the same directions on the "
               "grid of half the resolution; the lattice carries the later events (1: the second "
               "alone)"),
       setting("tolerance", &S::tolerance, 1e-6, 0.5, kept("diffusion"),
               "relative change per check that ends the diffusion"),
       setting("max_steps", &S::max_steps, 1, 1000000, kept("diffusion"),
               "lattice steps per diffusion, at most"),
       setting("check_every", &S::check_every, 1, 1024, kept("diffusion"),
               "lattice steps between convergence checks"),
       flag("warm", &S::warm, frame(), "1: start the diffusion from the last state"),
       setting("skip_multiple", &S::skip_multiple, 0, 1, frame(),
               "skip the lattice when a scattered photon's chance to scatter again, 1 - exp(-max "
               "sigma_s x "
               "longest side), is under this"),
       flag("measure", &S::measure, frame(),
            "1: after a diffusion, time 16 more lattice steps and 16 copies of its state (stage "
            "bandwidth)"),
       setting("interleave", &S::interleave, 0, 4096, kept("lights"),
               "k > 0: march in rounds of k steps, each followed by k x step lattice steps (the "
               "paper's Table I); "
               "0: march, then diffuse")},
      [](const LblSettings& s) {
        if (s.directions == 18 && s.blocked)
          throw ValidationError("settings.blocked",
                                "the 18-direction lattice runs on the whole grid only (blocked 0)");
      });
  return table;
}

LblSettings LblSettings::read(const Settings& settings) {
  return lbl_settings().read(settings);
}

const PipelineInfo& lbl_info() {
  static const PipelineInfo info = describe<LblPipeline>(
      lbl_settings(),
      {.summary = "single and multiple scattering with refraction: light rays marched by the ray "
                  "equation deposit "
                  "what they scatter, a lattice-Boltzmann diffusion spreads it, eye rays gather "
                  "both; kept across "
                  "camera moves, OpenCL",
       .method = "docs/pipelines/lbl.md (papers/lbl-scattering-refraction.md)",
       .terms = {Terms::Surface, Terms::Single, Terms::Multiple, Terms::All},
       .default_terms = Terms::All,
       .qualities = {{"draft", {{"rays", 1}, {"tolerance", 0.003}}},
                     {"normal", {}},
                     {"high", {{"rays", 3}, {"directions", 18}, {"tolerance", 0.0003}}}}});
  return info;
}

const PipelineInfo& LblPipeline::info() const {
  return lbl_info();
}

}  // namespace scatter
