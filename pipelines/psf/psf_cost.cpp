// PsfPipeline::estimate: the medium psf_pipeline.cpp's prepare() uploads and the light volumes and
// pyramids light_pyramid.cpp builds per light (all kept while the lights stay).
#include <algorithm>
#include <cmath>

#include "pipelines/cost_support.hpp"
#include "pipelines/psf/orders.hpp"
#include "pipelines/psf/psf_pipeline.hpp"

namespace scatter {

CostEstimate PsfPipeline::estimate(const Scene& scene, const RenderRequest& request, bool bake) {
  using namespace cost;
  PsfSettings s = PsfSettings::read(request.settings);
  Ledger upload, lights;
  if (bake) return upload.finish("psf");  // needs no bake
  const GridShape g = grid_shape(scene, 1);
  const double n = g.count(), px = double(scene.width) * scene.height;
  const std::string grid = g.text() + " voxels";
  // prepare() (called by plan()): voxelize(), then upload_medium(), as the reference's.
  add_medium_upload(upload, scene, g);

  // Per light (build_light_volume): l0, path, tau (float4 each) and the pyramid's levels
  // (float4, 8/7 of a volume), kept in medium_.lights; while one builds, its source volume and
  // the first level's two blur buffers (1/4 of a volume) besides, and ~1.25 volumes more that
  // the measurement shows (cost_test: 82^3 and 2 lights peaked 23 MB above the buffers).
  // Measured RSS: 130^3 and 4 lights 888 MB, 66^3 and 4 lights 305 MB (with ~220 MB of
  // contexts).
  const int count = static_cast<int>(scene.lights.size());
  double per_light = n * 16 * (3 + 8.0 / 7), transient = n * 16 * 2.5;
  // Model 1's orders (orders.cpp) on pyramid level L (n / 8^L voxels): 4 float4 bands kept, 6
  // float4 buffers while they build. L as orders_level chooses it at density 1.
  const bool orders = s.model == 1 && request.terms != Terms::Single;
  double level_voxels = 0;
  if (orders) {
    psf::OrderParams op{.g = scene.medium.g, .level = s.level};
    const Vec3 ss = scene.medium.sigma_s, sa = scene.medium.sigma_a;
    op.mean_sigma_t = {ss.x + sa.x, ss.y + sa.y, ss.z + sa.z};
    const int levels = static_cast<int>(psf::pyramid_layout(g.nx, g.ny, g.nz).size());
    const int level = psf::orders_level(op, static_cast<float>(g.voxel), levels);
    level_voxels = n / std::pow(8.0, level);
    per_light += level_voxels * 16 * 4;
    // The orders' working volumes: 6, and 5 more for conserve's normalisation.
    transient = std::max(transient, level_voxels * 16 * (s.conserve ? 11 : 6));
  }
  lights.device("scene.voxels", n * 28, grid + " x 28 B (sigma_s, sigma_t, occupancy)");
  lights.device("scene.voxels", count * per_light + (count ? transient : 0),
                std::to_string(count) + " lights x " + grid + " x 66 B (light volumes, pyramids" +
                    (orders ? ", orders)" : ")"));
  lights.device("scene.image.width", px * 12, "the image's buffer");
  lights.host("scene.image.width", px * 24, "zeros and the image");
  // Light volume: every voxel marches to its light (~side steps): measured 130^3 x 4 lights 14.7 s
  // (12.8 ns a voxel step), 66^3: 11 ns; pyramid ~60 ns a voxel. Taken at 25 and 100 ns.
  const double side = std::max({g.nx, g.ny, g.nz});
  lights.time(
      "scene.lights", count * n * (side * 25e-9 + 100e-9),
      std::to_string(count) + " lights x " + grid + " x " + std::to_string(int(side)) + " steps");
  // March per light: covered pixels x (side / step) steps, each looking up the pyramid along
  // ~side / step more: measured 4096 px x 4 lights 130^3 1.8 s, 256^2 px 66^3 3.7 s (25 ns a
  // unit with coverage 0.4). Taken at 35 ns.
  const double steps = side / s.step, covered = px * coverage(scene);
  if (orders) {
    // Model 1 reads its bands once a sub-step: 512^2 sphere, 66 steps, 2.3 s on a loaded CPU
    // where model 0 took 10.3 s (estimated below at 16.8 s): in the same proportion, 500 ns a
    // covered pixel and step.
    // Its orders, ~40 orders x 3 Gaussians x 3 axes over the level's voxels, ~60 taps each:
    // 228 ms at 33^3 in the same run, taken at 0.3 ns a tap.
    lights.time("scene.image.width", std::max(count, 1) * covered * steps * 500e-9,
                std::to_string(int(covered)) + " covered px x " + std::to_string(count) +
                    " lights x " + std::to_string(int(steps)) + " steps");
    lights.time("scene.lights", count * level_voxels * 40 * 9 * 60 * 0.3e-9,
                std::to_string(count) + " lights x " + std::to_string(int(level_voxels)) +
                    " voxels x ~40 orders");
  } else {
    lights.time("scene.image.width", std::max(count, 1) * covered * steps * steps * 35e-9,
                std::to_string(int(covered)) + " covered px x " + std::to_string(count) +
                    " lights x (" + std::to_string(int(steps)) + " steps)^2");
  }
  upload.peak_of(lights);
  return upload.finish("psf");
}

}  // namespace scatter
