// `single` in the registry: its settings table and description.
#include "core/errors.hpp"
#include "pipelines/registry.hpp"
#include "pipelines/single/sh.hpp"
#include "pipelines/single/single_pipeline.hpp"

namespace scatter {

const SettingsTable<SingleSettings>& single_settings() {
  using S = SingleSettings;
  using B = SingleBakeParams;
  static const SettingsTable<SingleSettings> table(
      "single",
      {setting("directions", &S::bake, &B::directions, 8, 1024, baked(),
               "directions of the optical-depth sweeps"),
       setting("samples", &S::bake, &B::samples, 16, 400'000, baked(),
               "Gaussian samples the bake keeps"),
       setting(
           "sh_order", &S::bake, &B::sh_order, 2, kMaxShBands, baked(),
           "spherical-harmonic bands: sh_order^2 coefficients per channel (the paper: up to 5)"),
       setting("sh_depth", &S::bake, &B::sh_depth, 0, 1, baked(),
               "1: project the optical depth, exponentiated when shading; 0: the transmittance "
               "(the paper)"),
       setting("radius", &S::bake, &B::radius, 0.2, 2.0, baked(),
               "Gaussian sigma over the local sample spacing"),
       setting("candidates", &S::bake, &B::candidates, 2, 10, baked(),
               "candidates per sample for the elimination"),
       setting("density_guide", &S::bake, &B::density_guide, 0, 1, baked(),
               "1: the sample density also follows |grad sigma_t| inside the medium"),
       setting("weight_fit", &S::bake, &B::weight_fit, 0, 200, baked(),
               "least-squares (CGLS) iterations refining the weights after the passes"),
       setting("split", &S::bake, &B::split, 0.0, 1000.0, baked(),
               "extinction ratio above which a Gaussian is split at the jump into two clipped "
               "pieces (0: never; "
               "else at least 1.5)"),
       setting("sigma_fit", &S::bake, &B::sigma_fit, 0, 16, baked(),
               "passes fitting each sample's sigma_s so the splatted field matches the voxels"),
       setting("adapt", &S::bake, &B::adapt, 0.0, 1.0, baked(),
               "the spacing's range [r/2, 2r] raised to this power: 1 the paper's rule, 0 uniform"),
       setting("seed", &S::bake, &B::seed, 0, 1 << 30, baked(), "random seed of the sampling"),
       setting("splat_scale", &S::splat_scale, 0.0, 1.0, frame(),
               "the splat's size over the image's, upsampled along the view rays' chords (0: one "
               "pixel in s x s, s up to 6, while the median Gaussian spans at least 1.5 of the "
               "splat's pixels; else at least 0.16: one in 6 x 6)"),
       flag("coarse", &S::coarse, frame(),
            "1: splat the bake's coarse set, a quarter of the samples (their progressive order "
            "makes them Poisson-disk) widened by 4^(1/3), with weights fitted for them (the live "
            "view's moving frames; needs exact_tr)"),
       flag("clip_back", &S::clip_back, frame(),
            "1: clip to the medium's first two intervals along the ray by depth peeling; 0: the "
            "paper's "
            "front-only clipping"),
       flag("exact_tr", &S::exact_tr, frame(),
            "1: each sample's optical depths to the eye and the lights through the voxels; 0: from "
            "its SH (the "
            "paper)"),
       flag("tr_gradient", &S::tr_gradient, frame(),
            "with exact_tr: the transmittance over each Gaussian as exp of a linear optical depth, "
            "which moves and "
            "scales it"),
       setting("tr_gradient_max", &S::tr_gradient_max, 0.0, 1000.0, frame(),
               "bound on |gradient| x sigma (1000: none in practice; the splat's depth cut keeps "
               "the model's "
               "transmittance at most one)"),
       flag("tr_hessian", &S::tr_hessian, frame(),
            "with tr_gradient: the optical depth's curvature per axis stretches or narrows each "
            "Gaussian"),
       flag("mesh_bound", &S::mesh_bound, frame(),
            "with exact_tr: optical depths through the mesh's medium, per unit medium and cut by a "
            "plane in each boundary voxel, not the voxels' means (dense media; "
            "docs/pipelines/single.md)")},
      [](const SingleSettings& s) {
        s.bake.check();
        if (s.splat_scale > 0 && s.splat_scale < 0.16)
          throw ValidationError("settings.splat_scale",
                                "splat_scale must be 0 (auto) or within [0.16, 1] (got " +
                                    std::to_string(s.splat_scale) + ")");
      });
  return table;
}

SingleSettings SingleSettings::read(const Settings& settings) {
  return single_settings().read(settings);
}

const PipelineInfo& single_info() {
  static const PipelineInfo info = describe<SinglePipeline>(
      single_settings(),
      {.summary = "single scattering in any medium from baked Gaussian samples with "
                  "spherical-harmonic optical "
                  "depth, splatted along the view rays and clipped by depth peeling, OpenGL",
       .method = "docs/pipelines/single.md (papers/single-scattering-inhomogeneous.md)",
       .terms = {Terms::Single},
       .default_terms = Terms::Single,
       // Shares measured on the bunny at 64^3, 128 directions, 25k samples (docs/BENCHMARKS.md).
       .bake_stages = {{"voxelize", 0.03},
                       {"ddod", 0.3},
                       {"divergence", 0.01},
                       {"sampling", 0.1},
                       {"gaussians", 0.3},
                       {"sh", 0.26}},
       .bake_key =
           [](const Scene& scene, const Settings& s) {
             return SinglePipeline::product_key(scene, single_settings().read(s));
           },
       .qualities = {{"draft", {{"samples", 5000}, {"directions", 64}}},
                     {"normal", {}},
                     {"high", {{"samples", 100000}, {"directions", 256}}}},
       // While the user drags: the coarse set (a quarter of the samples), splatted at half size,
       // each with the transmittance at its centre (docs/BENCHMARKS.md: the single drag).
       .moving = {{"coarse", 1}, {"splat_scale", 0.5}, {"tr_gradient", 0}}});
  return info;
}

const PipelineInfo& SinglePipeline::info() const {
  return single_info();
}

}  // namespace scatter
