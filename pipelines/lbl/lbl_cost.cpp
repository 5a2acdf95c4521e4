// LblPipeline::estimate: what lbl_pipeline.cpp's render() builds for a new material (volume,
// device volume, lattice) and each frame (light rays, deposit, view), and its lattice steps.
#include <algorithm>
#include <cmath>

#include "pipelines/cost_support.hpp"
#include "pipelines/lbl/lbl_frame.hpp"
#include "pipelines/lbl/lbl_pipeline.hpp"
#include "pipelines/lbl/light_rays.hpp"

namespace scatter {

CostEstimate LblPipeline::estimate(const Scene& scene, const RenderRequest& request, bool bake) {
  using namespace cost;
  LblSettings s = LblSettings::read(request.settings);
  if (request.terms == Terms::Surface)  // surface_request(): the surface pipeline with shadows on
    return SurfacePipeline::estimate(scene, {Terms::Surface, {{"shadows", 1}}, {}}, bake);
  Ledger l;
  if (bake) return l.finish("lbl");  // needs no bake
  const int margin = 1 + static_cast<int>(std::ceil(3 * s.smooth));
  const GridShape g = grid_shape(scene, margin, s.blocked ? s.block : 1);
  const double n = g.count(), px = double(scene.width) * scene.height;
  const std::string grid = g.text() + " nodes";
  const double d = s.directions;
  // All alive at once inside render()'s `if (d.material)` block (the VoxelGrid lives to its end):
  //   VoxelGrid 29 B; Volume (volume.hpp: sigma_s, sigma_t, occupancy, n, grad) 44 B;
  //   LatticeCoefficients (six arrays of 3 floats, all resized in volume.cpp) 72 B, until the
  //   Lattice is made; ClVolume (upload_volume) 40 B; Lattice (lattice.cpp): pt, ps, w 36 B
  //   (18 directions: and the diagonals' 36 B), src and irr 24 B, f_[2] 2 x 3 x directions
  //   floats, iface_ (blocked) 2 x 72 / block B; deposit 12 B and (g != 0) source 12 B, flow
  //   24 B and (flux_phase, 6 directions) the lattice's flux 12 B; the second scattering's
  //   gather (second.cpp, 6 directions, not interleaved) sigma_t' 12 B, its half-resolution grid
  //   and source 3 B, the sampling's mode 1 B, samples, their directions and list 3.5 B, second and
  //   its direction 24 B (host: sigma_t' and the sampling, 13 B); with gathers > 1 the last
  //   order 12 B and the half-resolution grid's sigma_t', source, phi V and cell list 5 B (host:
  //   its sigma_t', sums and list, 5 B).
  // Measured RSS: 72^3 346 MB, 104^3 628 MB (estimates 370, 671 with ~220 MB of contexts).
  const bool second = s.second && d == 6 && s.interleave == 0 && request.terms != Terms::Single;
  const bool orders = second && s.gathers > 1;
  double host = kGridBytes + 44 + 72 + (second ? 13 : 0) + (orders ? 5 : 0);
  double device = 40 + 36 * (d == 18 ? 2 : 1) + 24 + 2 * 12 * d +
                  (s.blocked ? 144.0 / s.block : 0) + 12 +
                  (scene.medium.g != 0 ? 12 + 24 + (d == 6 && s.flux_phase ? 12 : 0) : 0) +
                  (second ? 43.5 : 0) + (orders ? 17 : 0);
  l.host("scene.voxels", n * host,
         grid + " x " + short_number(host) + " B (grid, volume, coefficients)");
  l.device("scene.voxels", n * device,
           grid + " x " + short_number(device) + " B (volume, lattice, deposit)");
  // Light rays (light_rays.cpp): side^2 per light, kRayFloats floats each, on the host and the
  // device.
  const double radius =
      0.5 * std::sqrt(double(g.nx) * g.nx + double(g.ny) * g.ny + double(g.nz) * g.nz);
  const double side = std::clamp(std::ceil(s.rays * 2 * radius), 2.0, 4096.0);
  const double rays = double(scene.lights.size()) * side * side;
  const std::string ray_text =
      std::to_string(scene.lights.size()) + " lights x " + std::to_string(int(side)) + "^2 rays";
  l.host("scene.lights", rays * lbl::kRayFloats * 4, ray_text + " x 48 B");
  l.device("scene.lights", rays * lbl::kRayFloats * 4, ray_text + " x 48 B (buffer)");
  l.device("scene.image.width", px * 12, "the image's buffer");
  l.host("scene.image.width", px * 12, "the image");
  // lobes (light_lobes > 1): each light's deposit 12 B and flow 24 B a node.
  const int lobes = lbl::light_lobes(scene, s);
  if (lobes > 1)
    l.device(
        "scene.lights", n * 36.0 * lobes,
        std::to_string(lobes) + " lobes x " + grid + " x 36 B (each light's or group's deposit)");

  // Volume: measured 72^3 0.37-0.55 s, 104^3 1.75 s (~1.5 us a node with the voxelizer).
  // What a kept state skips (Pipeline::keeps): everything but the view.
  double kept = voxelize_seconds(scene, n) + n * 1.5e-6;
  l.time("scene.voxels", kept, grid + " volume and lattice built");
  // March: ~2 radius / step steps a ray. Measured 62,500 rays x 250 steps 1.4 s (89 ns); x 4
  // lights 2.4 s. Taken at 120 ns.
  const double ray_steps = 2 * radius / s.step;
  kept += rays * ray_steps * 120e-9;
  l.time("settings.rays", rays * ray_steps * 120e-9,
         ray_text + " x " + std::to_string(int(ray_steps)) + " steps");
  // Diffuse: ~30 ns a node a step (docs/BENCHMARKS.md: 11 ms a step at 72^3, 75 ms at 136^3);
  // convergence took 290-550 steps on the sphere (64-96 voxels); taken as 600 + 60 x the optical
  // diameter, at most max_steps. 18 directions: measured 55 s against 5.4 s at 72^3 (10x).
  const MediumBounds m = medium_bounds(scene);
  const double tau = m.sigma_t * g.longest;
  const bool multiple =
      request.terms != Terms::Single && -std::expm1(-m.sigma_s * g.longest) >= s.skip_multiple;
  if (multiple) {
    const double steps = std::min<double>(s.max_steps, 600 + 60 * tau);
    kept += steps * n * 30e-9 * (d == 18 ? 10 : 1);
    l.time("settings.max_steps", steps * n * 30e-9 * (d == 18 ? 10 : 1),
           std::to_string(int(steps)) + " lattice steps x " + grid);
    // The second scattering's gather, each light change: 32 rays from a voxel in 8 and those
    // next to surfaces, across the grid; measured 0.71-1.44 s at 72^3 (the shipped scenes at
    // 64 voxels, escape_stride 2, escape_far 4), taken as 60 ns a node per voxel of the long
    // side. The sampling (sphere, layers): escape_stride 1 gathers at every voxel, 5.9-6.8x the
    // time with its rays on the voxels all the way (escape_far 0 alone: 1.8x), so taken as 3.5x
    // for the sampling; 3 and 4 take 1.15x and 1.2x (more voxels next to a surface are computed
    // themselves). The far field: a ray of L voxels (half the long side on average) takes
    // far + (L - far) / 2 steps, L at far 0 (measured: far 16 1.28x, the model 1.33x).
    if (second) {
      const double side_voxels = std::max({g.nx, g.ny, g.nz});
      const double sampling = s.escape_stride == 1   ? 3.5
                              : s.escape_stride == 2 ? 1.0
                              : s.escape_stride == 3 ? 1.15
                                                     : 1.2;
      const double far = s.escape_stride > 1 ? s.escape_far : 0, L = side_voxels / 2;
      auto gather_steps = [&](double f) { return f > 0 ? std::min(L, f + (L - f) / 2) : L; };
      const double t = n * side_voxels * 60e-9 * sampling * gather_steps(far) / gather_steps(4);
      kept += t;
      l.time("settings.second", t,
             "the second scattering's gather over " + grid + " (escape_stride " +
                 std::to_string(s.escape_stride) + ", escape_far " + short_number(far) + ")");
      // The later orders (setting gathers), each on the half-resolution grid at every cell near
      // the medium: measured 0.14-0.47x the gather's time at the defaults each (bunny, layers,
      // cube-torus, sphere at g 0.7), taken as 0.45x of its model at the defaults.
      if (orders) {
        const double each = 0.45 * n * side_voxels * 60e-9;
        kept += each * (s.gathers - 1);
        l.time("settings.gathers", each * (s.gathers - 1),
               "orders 3 to " + std::to_string(s.gathers + 1) +
                   " gathered on the half-resolution grid");
      }
    }
  }
  // View: a ray a pixel through the grid; measured 4096 px x 250 steps 66 ms (65 ns a step).
  l.time("scene.image.width", px * ray_steps * 100e-9,
         std::to_string(scene.width) + "x" + std::to_string(scene.height) + " px viewed");
  CostEstimate e = l.finish("lbl");
  e.kept_seconds = std::min(kept, e.seconds);
  return e;
}

}  // namespace scatter
