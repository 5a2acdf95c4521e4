// SinglePipeline::estimate: the bake (single_bake.cpp, single_gaussians.cpp, sampling.cpp) and a
// frame (single_pipeline.cpp, single_shade_exact.cpp). A render on a cache miss bakes first,
// so a render's estimate includes the bake unless the request says it is baked already.
#include <algorithm>
#include <cmath>
#include <thread>

#include "pipelines/cost_support.hpp"
#include "pipelines/single/sh.hpp"
#include "pipelines/single/single_pipeline.hpp"

namespace scatter {
namespace {

// Peak of the bake: voxel-sized arrays alive in make_gaussians (its accumulators are per thread).
void bake_memory(cost::Ledger& l, const cost::GridShape& g, const SingleBakeParams& p,
                 size_t threads) {
  const double n = g.count(), samples = p.samples, nc = sh_count(p.sh_order);
  const std::string grid = g.text() + " voxels";
  // VoxelGrid 29 B; bake_single's moment 12, rho 4, q 4, layer 1, anchor 8, cdf 8 (doubles);
  // make_gaussians: sum + partial (a double per voxel per thread), field + fpart (3 doubles per
  // voxel per thread), CGLS r and q (2 doubles).
  const double per_voxel = cost::kGridBytes + 37 + 8.0 * threads + 24.0 * threads + 16;
  l.host("scene.voxels", n * per_voxel,
         grid + " x " + short_number(per_voxel) + " B (grid and bake arrays, " +
             std::to_string(threads) + " threads)");
  // Candidates (samples x candidates): position, q, voxel (36 B) and the elimination's
  // neighbour lists (~25 (index, distance) pairs, the hash grid): ~400 B each (its comment: ~1 GB
  // at the 2.5M bound).
  l.host("settings.samples", samples * p.candidates * 400,
         std::to_string(p.samples) + " samples x " + std::to_string(p.candidates) +
             " candidates x 400 B");
  // The product: up to 2 pieces a sample (split), 15 floats + 3 x sh_order^2 each; serialised
  // once into the cache (a second copy).
  l.host("settings.samples", 2 * 2 * samples * (15 + 3 * nc) * 4,
         std::to_string(p.samples) +
             " samples x (15 + 3 x sh_order^2) floats x 2 pieces x 2 copies (product, serialised)");
}

}  // namespace

CostEstimate SinglePipeline::estimate(const Scene& scene, const RenderRequest& request, bool bake) {
  using namespace cost;
  SingleSettings s = SingleSettings::read(request.settings);
  const SingleBakeParams& p = s.bake;
  const GridShape g = grid_shape(scene, kSingleGridMargin);
  const double n = g.count(), px = double(scene.width) * scene.height;
  const double samples = p.samples, nc = sh_count(p.sh_order), side = std::max({g.nx, g.ny, g.nz});
  const size_t threads = std::max(1u, std::thread::hardware_concurrency());
  const std::string grid = g.text() + " voxels";

  Ledger baking;
  bake_memory(baking, g, p, threads);
  // Times measured on the bunny on an idle machine (docs/BENCHMARKS.md, today's defaults: 64^3
  // 9.3 s, 128^3 48 s): ddod ~40 ns a voxel-direction, sampling ~26 us a candidate, gaussians
  // ~200 ns a voxel a pass (4 + 2 x weight_fit + sigma_fit passes), sh ~8-27 ns a
  // sample-direction-voxel step. Taken at 80 ns, 25 us x sqrt(candidates / 25000) (sphere 56^3
  // here: 25k candidates 0.95 s, 100k 9.8 s), 400 ns and 40 ns. With four builds sharing the two
  // cores the same bakes ran 3-6x longer (sphere 56^3, 5000 samples: ddod 4.4 s, gaussians 8.3 s).
  baking.time("scene.voxels", voxelize_seconds(scene, n), grid + " voxelized");
  baking.time("settings.directions", n * p.directions * 80e-9,
              grid + " x " + std::to_string(p.directions) + " directions (ddod)");
  const double candidates = samples * p.candidates;
  baking.time(
      "settings.samples",
      candidates * 25e-6 * std::sqrt(std::max(1.0, candidates / 25000)) + n * 1e-6,
      std::to_string(p.samples) + " x " + std::to_string(p.candidates) + " candidates eliminated");
  const double passes = 4 + 2.0 * p.weight_fit + p.sigma_fit;
  baking.time("scene.voxels", n * passes * 400e-9,
              grid + " x " + short_number(passes) + " Gaussian passes");
  baking.time("settings.directions", samples * p.directions * side * 40e-9,
              std::to_string(p.samples) + " samples x " + std::to_string(p.directions) +
                  " directions x " + std::to_string(int(side)) + " steps (sh)");
  if (bake) return baking.finish("single");

  Ledger frame;
  // Kept for the frames: current_.grid (29 B a voxel) and exact_tr's cl_sigma_t_ (12 B); the
  // samples in GL buffers (upload(): 108 B + the SH) and OpenCL (shade_exact: 108 B), the
  // transmittance to each light kept by its place (36 B a sample a light), and five render
  // targets (front, back, third, fourth, out: 20 B a pixel each) with the read-back.
  const double pieces = 2 * samples, lights = std::max<size_t>(scene.lights.size(), 1);
  frame.host("scene.voxels", n * kGridBytes, grid + " x 29 B (the grid kept for exact_tr)");
  frame.host("settings.samples", 2 * samples * (15 + 3 * nc) * 4, "the product");
  // sigma_t; with mesh_bound the bounded medium's and its planes as well.
  const double voxel_bytes = s.exact_tr ? (s.mesh_bound ? 40 : 12) : 0;
  frame.device("scene.voxels", n * voxel_bytes,
               grid + " x " + std::to_string(int(voxel_bytes)) + " B (sigma_t, planes)");
  frame.device(
      "settings.samples",
      pieces * (108 + 12 * nc + (s.exact_tr ? 108 + 2 * 36 * lights + (s.mesh_bound ? 12 : 0) : 0)),
      std::to_string(p.samples) + " samples' buffers");
  frame.device(
      "scene.image.width", px * 5 * 20,
      std::to_string(scene.width) + "x" + std::to_string(scene.height) + " px x 5 targets x 20 B");
  frame.host("scene.image.width", px * 28, "the read-back");
  // Shade (exact_tr): each sample marches ~side voxels to the eye and to each light. Splat:
  // per covered pixel ~9 x (side / spacing) overlapping Gaussians (3-sigma quads, spacing ~
  // longest / cbrt(samples)).
  // coarse: a quarter splatted, its Gaussians widened (so fewer overlap a pixel).
  const double drawn =
      s.coarse && s.exact_tr && coarse_count(p.samples) > 0 ? samples / 4 : samples;
  if (s.exact_tr)
    frame.time("settings.samples", 2 * drawn * (1 + lights) * side * 20e-9,
               std::to_string(int(std::lround(drawn))) + " samples x " +
                   std::to_string(int(lights + 1)) + " rays");
  // splat_scale: one pixel in stride x stride splatted (auto: by the sigma the spacing of
  // `samples` in the mesh's box gives, at least kMinSigmaVoxels; a sigma floored above the
  // spacing's widens each pixel's tube of Gaussians by its square).
  Aabb box = scene.mesh->bounds();
  const Vec3 size = box.size();
  const double spaced = p.radius * std::cbrt(size.x * size.y * size.z / drawn);
  const double least = kMinSigmaVoxels * std::max({size.x, size.y, size.z}) / scene.voxels;
  const double sigma = std::max(spaced, least);
  const double overlap = 9 * std::cbrt(drawn) * (sigma / spaced) * (sigma / spaced);
  const int stride = splat_stride(s.splat_scale, sigma, scene);
  frame.time("scene.image.width",
             px * coverage(scene) * overlap * 60e-9 / (stride * stride) + px * 4 * 200e-9,
             std::to_string(scene.width) + "x" + std::to_string(scene.height) + " px x " +
                 std::to_string(int(overlap)) + " Gaussians splatted" +
                 (stride > 1 ? " at one pixel in " + std::to_string(stride * stride) : ""));
  baking.peak_of(frame);
  return baking.finish("single");
}

}  // namespace scatter
