// `single`: single scattering inside inhomogeneous materials from baked samples
// (papers/single-scattering-inhomogeneous.md). The bake (single_bake.hpp) places Gaussian samples
// carrying spherical harmonics of their direction-dependent optical depth; it is content-addressed
// by the asset (pipelines/asset_key) and the bake settings, and kept in the BakeCache. A frame:
//   depth_peel  the mesh's first four surfaces from the eye (distance textures)
//   shade       per sample (compute shader): weight * sigma_s * psi(to eye) * sum over lights of
//               E * psi(to light) * phase, so the fragment work does not grow with the lights
//   splat       per sample a camera-facing quad; per fragment the Gaussian's integral along the
//               ray over the ball's chord within the medium (first to second and third to fourth
//               surface by depth peeling; the paper: from the first surface on)
//               (erf), added into a float target
//
// Settings: the table in pipelines/single/single_info.cpp (`scatterd pipelines`,
// docs/pipelines/single.md). exact_tr (the default) sums each sample's optical depth to the eye
// (every frame) and to every light (when it appears or moves) through the voxels
// (kernels/single/shade.cl); 0 reads them from the samples' SH, the paper's method (measured: the
// SH's 25 coefficients are most of the error on faces and shadows, docs/BENCHMARKS.md). The term is
// the single-scattered radiance; the surface, refraction and Fresnel at the boundary are not
// included (ior is neglected, and the plan says so).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "gpu/cl_context.hpp"
#include "gpu/gl_objects.hpp"
#include "pipelines/common/raster.hpp"
#include "pipelines/cost.hpp"
#include "pipelines/pipeline.hpp"
#include "pipelines/settings_table.hpp"
#include "pipelines/single/single_bake.hpp"

namespace scatter {

// With exact_tr, the splat takes the phase per view ray where |g| is at least kPerRayPhaseG (a
// peaked phase is narrower than a Gaussian seen from the camera), or where the eye lies within
// kNearEyeSigmas of the bake's median sigma (the whole set's, so that coarse frames agree) of the
// object's box (inside it too): a Gaussian
// beside or around the eye spans a wide cone of view rays, and the direction to its centre is
// none of theirs (from inside a box lit from the camera's side, the phase at the centres put the
// single term 1.3x high). Elsewhere, per sample at its centre, which costs the fragment nothing
// (docs/pipelines/single.md).
inline constexpr double kPerRayPhaseG = 0.5, kNearEyeSigmas = 30;
bool phase_per_ray(const Scene& scene, double sigma_median);

// splat_scale 0 (auto) splats one pixel in s x s, s the largest stride (up to kMaxSplatStride)
// at which the median Gaussian's sigma still spans this many of the splat's pixels at the
// medium's near side, then upsamples along the chords (shaders/single/upsample.frag): the splat's
// fragments fall s^2 times where they are many and the field is smooth over a pixel. Measured at
// 512 x 512 on the shipped scenes (sigma 8-9 pixels): stride 2 -> 4 is 1.5-2.3x faster and a
// little closer to the reference; 4 -> 5 (1.5 pixels) moved the error by -0.10 to +0.09 points
// at 0.6-0.8x the splat's time, 6 by up to +0.4 points (docs/BENCHMARKS.md).
inline constexpr double kSplatSigmaPx = 1.5;
inline constexpr int kMaxSplatStride = 6;

// The pixels per world unit at the medium's near side (its bounding sphere's), where splat_scale
// auto measures the Gaussians.
double near_pixels_per_unit(const Scene& scene);
// The splat's stride for a splat_scale `scale` (0: auto, by a median Gaussian sigma `sigma`).
inline int splat_stride(double scale, double sigma, const Scene& scene) {
  if (scale > 0) return std::clamp(int(std::lround(1 / scale)), 1, kMaxSplatStride);
  return std::clamp(int(sigma * near_pixels_per_unit(scene) / kSplatSigmaPx), 1, kMaxSplatStride);
}

// The samples a frame splats: all, or (coarse) the bake's coarse set, the first coarse_count of
// its progressive order and the pieces split off them, as index ranges (first, count), each
// Gaussian's sigma times sigma_scale so that the fewer fill the same volume, with the coarse
// weights (pipelines/single/single_prefix.cpp).
struct DrawnSamples {
  std::vector<std::pair<int, int>> ranges;
  double sigma_scale = 1;
  bool coarse = false;
  int count() const {
    int n = 0;
    for (const auto& r : ranges) n += r.second;
    return n;
  }
};
DrawnSamples drawn_samples(const SingleBake& bake, bool coarse);

struct SingleSettings {
  SingleBakeParams bake;
  double splat_scale = 0.0;  // 0: auto (above); else the splat's size over the image's, >= 0.16
  bool coarse = false;  // the bake's coarse set (a quarter of the samples, widened, own weights)
  bool clip_back = true;
  bool exact_tr = true;
  bool tr_gradient = true;
  double tr_gradient_max = 1000.0;
  bool tr_hessian = true;
  bool mesh_bound = false;  // exact_tr's optical depths bounded by a plane per boundary voxel
  static SingleSettings read(const Settings& settings);
};
// The settings table (pipelines/single/single_info.cpp).
const SettingsTable<SingleSettings>& single_settings();

class SinglePipeline : public Pipeline {
 public:
  // What render() (bake: bake()) of `scene` will cost, without a GPU or an instance
  // (pipelines/cost.hpp); throws ValidationError for settings render() would reject.
  static CostEstimate estimate(const Scene& scene, const RenderRequest& request, bool bake);
  // The key the bake of `scene` with `settings` is cached under (and its bake job named by).
  static std::string product_key(const Scene& scene, const SingleSettings& settings);
  SinglePipeline(gpu::Gpu& gpu, BakeCache* cache);
  ~SinglePipeline() override;
  const PipelineInfo& info() const override;
  Plan plan(const Scene& scene, const RenderRequest& request) override;
  BakeResult bake(const Scene& scene, const RenderRequest& request,
                  const BakeProgress& progress = {}) override;
  RenderResult render(const Scene& scene, const RenderRequest& request) override;

  // The product the last bake() or render() used.
  const SingleBake* current() const { return current_.bake.get(); }
  // Per-sample colours of the last frame's shade pass (4 floats per sample), for tests.
  std::vector<float> read_shaded() const;
  // Per-sample offsets of the Gaussians' centres and their standard deviations per axis, 4 floats
  // each (exact_tr with tr_gradient), for tests.
  std::pair<std::vector<float>, std::vector<float>> read_moves() const;
  // exact_tr: how many per-light transmittance passes ran for the current bake (tests).
  int light_passes() const { return current_.light_passes; }

 private:
  struct Current {
    std::string fingerprint, key;  // both the product key (kept apart for the plan's text)
    std::shared_ptr<const SingleBake> bake;
    std::shared_ptr<const DensityField> density;  // keeps the fingerprinted address taken
    std::shared_ptr<const VoxelGrid> grid;        // the medium it was baked from (exact_tr)
    bool uploaded = false;
    bool cl_uploaded = false;
    bool cl_bounded = false;  // the mesh-bounded medium and anchors are uploaded (mesh_bound)
    // exact_tr: transmittance to each light and (tr_gradient) its optical depth's gradient, by
    // the light's place and whether the gradient was computed
    std::map<std::string, std::pair<cl::Buffer, cl::Buffer>> light_tr;
    int light_passes = 0;       // light_tr computations so far (tests)
    bool moved = false;         // shifts_ / axes_ hold exact_tr's last values
    double sigma_median = 0;    // the samples' median Gaussian sigma (splat_scale auto)
    double sigma_t_median = 0;  // the medium voxels' median extinction (the upsample's guide)
  };
  // The stages of a frame with settings `s` for the asset whose fingerprint is `fp`.
  Plan make_plan(const Scene& scene, Terms terms, const SingleSettings& s,
                 const std::string& fp) const;
  // What a frame's plan adds once the eye's place (`inside`: KeptMesh::eye_inside) and the
  // phase's evaluation (`per_ray`: phase_per_ray with exact_tr) are known
  // (pipelines/single/single_plan.cpp, with make_plan).
  static void note_frame(Plan& plan, const Scene& scene, const SingleSettings& s, bool inside,
                         bool per_ray);
  BakeResult bake(const Scene& scene, const SingleSettings& s, const std::string& fp,
                  const BakeProgress& progress);
  void upload();
  // The samples' own Gaussians in shifts_ (no move) and axes_ (sigma on every axis), and no
  // cuts (linear or quadratic) in cuts_.
  void reset_moves();
  // exact_tr: the per-sample factors by kernels/single/shade.cl, written into colors_.
  // With `gradient`, also each Gaussian's offset into shifts_ (kernels/single/shade.cl). Only the
  // `drawn` samples, their sigma scaled. `mesh_bound`: through the mesh-bounded medium
  // (pipelines/common/boundary_planes.hpp).
  void shade_exact(const Scene& scene, const DrawnSamples& drawn, bool gradient, bool hessian,
                   double max_gs, bool mesh_bound);
  // splat_scale: the image from `splat` (one pixel in stride x stride) and the image-size
  // distance textures front, back, third, fourth (pipelines/single/single_upsample.cpp); `inside`:
  // the eye is inside the object (KeptMesh::eye_inside); `per_ray`: the splat took the phase per
  // view ray, so the interpolation divides it out too (shaders/single/upsample.frag).
  Image upsample(const RenderTarget& splat, std::array<const RenderTarget*, 4> surfaces, int stride,
                 bool clip_back, bool inside, const Scene& scene, bool per_ray);

  gpu::Gpu& gpu_;
  BakeCache* cache_;
  KeptMesh mesh_;  // the depth peel's
  std::unique_ptr<BakeCache> own_cache_;
  Current current_;
  gpu::GlObject distance_program_, shade_program_, splat_program_, upsample_program_, empty_vao_;
  // The splat with the quadratic model's cut (QUAD_CUT, shaders/single/splat.frag): only frames
  // with tr_gradient and tr_hessian have one to apply.
  gpu::GlObject splat_quad_program_;
  gpu::GlObject positions_, weights_, sigma_s_, sh_, colors_, sigmas_, shifts_, axes_, planes_,
      cuts_, light_factors_;
  cl::Buffer cl_sigma_t_, cl_bounded_sigma_t_, cl_bound_, cl_bounded_at_, cl_at_, cl_position_,
      cl_sigma_, cl_weight_, cl_coarse_weight_, cl_sigma_s_, cl_plane_, cl_out_, cl_shift_,
      cl_axes_, cl_cut_, cl_light_factor_;
  size_t light_factor_floats_ = 0;  // the size of light_factors_ and cl_light_factor_
};

}  // namespace scatter
