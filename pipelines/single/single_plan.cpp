// The `single` pipeline's plan: the stages a frame runs and why (plan(), make_plan()), what a
// frame adds once it knows where the eye is and how the phase is taken (note_frame()), and
// phase_per_ray().
#include <cmath>
#include <string>

#include "pipelines/single/single_pipeline.hpp"

namespace scatter {

bool phase_per_ray(const Scene& scene, double sigma_median) {
  if (scene.lights.empty() || scene.medium.g == 0) return false;
  if (std::abs(scene.medium.g) >= kPerRayPhaseG) return true;
  const Aabb b = scene.mesh->bounds();
  const Vec3& e = scene.camera.position;
  const Vec3 out = vmax(vmax(b.lo - e, e - b.hi), Vec3{0, 0, 0});  // 0 on an axis inside the box
  return length(out) < kNearEyeSigmas * sigma_median;
}

Plan SinglePipeline::plan(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  SingleSettings s = SingleSettings::read(request.settings);
  return make_plan(scene, request.terms, s, product_key(scene, s));
}

Plan SinglePipeline::make_plan(const Scene& scene, Terms terms, const SingleSettings& s,
                               const std::string& fp) const {
  Plan p{name(), terms, {}};
  const bool same = current_.bake && current_.fingerprint == fp;
  p.stages.push_back({"voxelize", !same,
                      same ? "the asset is the one already baked"
                           : std::to_string(scene.voxels) + " voxels on the long side"});
  p.stages.push_back({"bake", !same,
                      same ? "reusing the loaded bake " + current_.key.substr(0, 12)
                           : "looked up by content (voxels + settings); baked on a miss: " +
                                 std::to_string(s.bake.directions) + " directions, " +
                                 std::to_string(s.bake.samples) + " samples, " +
                                 std::to_string(s.bake.sh_order * s.bake.sh_order) +
                                 " SH coefficients of " +
                                 (s.bake.sh_depth ? "optical depth" : "transmittance")});
  p.stages.push_back({"depth_peel", true,
                      s.clip_back
                          ? "four surfaces: the medium along each ray is [1st, 2nd] and [3rd, 4th]"
                          : "first surface (the paper's clipping)"});
  p.stages.push_back(
      {"shade", true,
       std::to_string(scene.lights.size()) + " lights evaluated once per sample, not per fragment" +
           (s.exact_tr ? std::string(": exact optical depths through the voxels (exact_tr)") +
                             (s.mesh_bound ? ", the medium bounded by a plane per "
                                             "boundary voxel (mesh_bound)"
                                           : "")
                       : std::string(": transmittance from the samples' SH"))});
  std::string moved;
  if (s.exact_tr && s.tr_gradient)
    moved = s.tr_hessian ? ", moved and stretched by the optical depth's gradient and curvature"
                         : ", moved by the optical depth's gradient";
  p.stages.push_back(
      {"splat", true, "one Gaussian per sample integrated along each view ray (erf)" + moved});
  if (scene.medium.ior != 1.0)
    p.stages.push_back(
        {"boundary", false,
         "refraction and Fresnel are neglected (ior " + std::to_string(scene.medium.ior) + ")"});
  if (scene.medium.g != 0.0)
    p.stages.push_back({"phase", true,
                        "Henyey-Greenstein g " + std::to_string(scene.medium.g) +
                            " evaluated per sample for its direction to the eye"});
  p.stages.push_back({"readback", true, "linear RGB to the host"});
  return p;
}

void SinglePipeline::note_frame(Plan& plan, const Scene& scene, const SingleSettings& s,
                                bool inside, bool per_ray) {
  for (StagePlan& stage : plan.stages) {
    if (stage.name == "depth_peel" && inside)
      stage.reason = s.clip_back ? "four surfaces, the eye inside the object: the medium along "
                                   "each ray is [eye, 1st] and [2nd, 3rd]"
                                 : "the eye inside the object: the medium is all ahead of it";
    if (stage.name == "shade" && inside && !s.exact_tr)
      stage.reason +=
          "; the eye is inside the object, where the SH's transmittance (to the boundary, past "
          "the eye) is not the eye's: exact_tr 1 computes it";
    if (stage.name == "phase" && per_ray)
      stage.reason = "Henyey-Greenstein g " + std::to_string(scene.medium.g) +
                     " evaluated per view ray towards each light in the splat (" +
                     (std::abs(scene.medium.g) >= kPerRayPhaseG
                          ? "a peaked phase"
                          : "the eye near the medium: a Gaussian near it spans a wide cone of "
                            "rays") +
                     ")";
  }
}

}  // namespace scatter
