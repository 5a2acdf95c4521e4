// ReferencePipeline::estimate: what reference_pipeline.cpp's render() allocates and how long it
// traces or marches (pipelines/cost.hpp).
#include <algorithm>

#include "pipelines/cost_support.hpp"
#include "pipelines/reference/reference_pipeline.hpp"

namespace scatter {

CostEstimate ReferencePipeline::estimate(const Scene& scene, const RenderRequest& request,
                                         bool bake) {
  using namespace cost;
  ReferenceSettings s = ReferenceSettings::read(request.settings);
  Ledger upload, frame;
  if (bake) return upload.finish("reference");  // nothing to bake
  const GridShape g = grid_shape(scene, 1);
  const double n = g.count(), px = double(scene.width) * scene.height;
  const std::string grid = g.text() + " voxels";
  // Peak while uploading (render: voxelize(), then upload_medium()); the grid lives to the end.
  add_medium_upload(upload, scene, g);
  const bool march = s.marches(request.terms);
  const bool mesh = scene.medium.ior != 1.0 || !s.voxel_boundary;
  // Made before the upload and alive through it where the mesh bounds the medium: the interior
  // depth (a byte a voxel, host and device) and, for a mesh of kCellListsMinTriangles or more
  // (or cells 1), the voxels' triangle lists (first 4 B, skip 1 B, host and device); each is
  // computed through a 4-byte-a-voxel distance array whose freed pages stay resident (measured:
  // 16 B a voxel at 146^3 for the sphere, `CostTest.ReferenceTracksMeasuredMemory`).
  const double tris = mesh ? double(scene.mesh->triangle_count()) : 0;
  const bool cells = mesh && s.builds_cell_lists(size_t(tris), request.terms);
  if (mesh) {
    upload.host("scene.voxels", n * (cells ? 10 : 5),
                grid + (cells ? " x 10 B" : " x 5 B") + " (interior depth" +
                    (cells ? ", cell lists)" : ")"));
    upload.device("scene.voxels", n * (cells ? 6 : 1),
                  grid + (cells ? " x 6 B" : " x 1 B") + " (the same on the device)");
  }
  // Later, per frame: the grid and two medium buffers stay; Monte Carlo adds sum, sum_sq, part
  // and batch_sq (device), zeros, their four host copies, the mean and the standard error
  // (host); the marcher one output buffer and the image.
  frame.host("scene.voxels", n * kGridBytes, grid + " x 29 B (grid)");
  frame.device("scene.voxels", n * 24, grid + " x 24 B (sigma_s, sigma_t)");
  frame.host("scene.image.width", px * (march ? 12 : 96),
             std::to_string(scene.width) + "x" + std::to_string(scene.height) + " px x " +
                 (march ? "12" : "96") + " B");
  frame.device("scene.image.width", px * (march ? 12 : 48), "the image's device buffers");
  if (mesh) {
    // FlatBvh (scene/bvh.hpp) on the host and its three buffers: ~2 nodes and 9 floats a triangle
    // (the mesh bounds the medium); the interior depth and the cell lists (above) and the
    // convexity check's edge map; a convex mesh's exit maps, per light about 4 cells (16 B) and 14
    // list entries (56 B) a triangle, and their build's vectors on the host (4.5x that).
    const double maps = s.exit_maps && !march ? double(scene.lights.size()) * tris * 72 : 0;
    frame.host("scene.mesh", tris * 100 + n * (cells ? 6 : 1) + tris * 3 * 48 + maps * 4.5,
               "BVH, interior depth, cell lists, edge map, exit maps");
    frame.device("scene.mesh", tris * 100 + n * (cells ? 6 : 1) + maps,
                 "BVH buffers, interior depth, cell lists, exit maps");
  }

  const double lights = std::max<size_t>(scene.lights.size(), 1), covered = px * coverage(scene);
  if (march) {
    // kernels/reference/single_march.cl: per covered pixel (voxels / step) steps along the view
    // ray, each marching (voxels / step) steps to every light. Measured: sphere 256^2 px, 64^3,
    // 1 light, step 0.25: 12.7 s = 7.4 ns a unit; taken as 15 ns.
    double per_side = scene.voxels / s.step;
    frame.time("settings.step", covered * lights * per_side * per_side * 15e-9,
               "march " + std::to_string(int(covered)) + " covered px x " +
                   std::to_string(int(lights)) + " lights x (voxels/step)^2");
  } else {
    // kernels/reference/path.cl: per path (1 + scattering events) vertices, each a free flight
    // and a shadow ray per light, crossing bricks of 8 voxels (more per unit length at finer
    // grids). Events: a/(1 - a) absorption-limited, tau + tau^2 (1 - g) / 2 escape-limited
    // (tau: the mean optical radius; a walk of N collisions spreads over 2 N l l / (1 - g) in
    // square, l the mean free path: a backward phase takes up to twice the collisions to leave,
    // a forward one fewer), max_depth at most; 1 for the single term. The long stress mode's
    // mixed/70 (albedo 1 - 1e-6, tau 78, g -0.99, 16 lights) took 5.5x the estimate with
    // tau^2 / 2; the planner then sent it to the path tracer for 171 s.
    // A dielectric reflects back in what reaches its boundary from inside: diffuse light with
    // the internal diffuse Fresnel reflectance F_dr (Egan and Hilgeman's fit, 0.45 at ior 1.3,
    // 0.65 at 1.6), so a walk takes 1 / (1 - F_dr) tries to leave, the escape-limited events that
    // many times.
    MediumBounds m = medium_bounds(scene);
    double tau = m.mean_sigma_t * g.longest / 2;
    const double eta = scene.medium.ior;
    const double f_dr =
        eta > 1 ? std::clamp(-1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta, 0.0, 0.95)
                : 0.0;
    double events =
        request.terms == Terms::Single
            ? 1.0
            : std::min({double(s.max_depth), m.albedo < 1 ? m.albedo / (1 - m.albedo) : 1e9,
                        (tau + tau * tau * (1 - scene.medium.g) / 2) / (1 - f_dr)});
    // Measured: sphere 258^3 6.7 us a path against 1.73 at 66^3 (3.9x).
    double bricks = 1 + scene.voxels / 32.0;
    // Opaque blockers give their bricks a huge majorant: null collisions.
    double blocker = scene.medium.density && scene.medium.density->blocker_sigma_a() > 0 ? 2.5 : 1;
    // Calibrated on docs/BENCHMARKS.md's 96^2 px x 256 spp frames (an idle machine): sphere
    // 1.61 s (71 ns a unit with bricks 1 + voxels / 64), layers 1.98 s (49 ns), bunny 1.01 s
    // (37 ns), cube-torus 12.5 s (~90 ns with the blocker's 2.5); taken as 70 ns with bricks
    // 1 + voxels / 32, and 0.2 us a path that misses. Here, with four engineers' builds sharing
    // the 2 cores, sphere 256^2 px spp 12 took 1.36 s (1 light, 181 ns a unit at 1 + voxels /
    // 64) and 7.9 s (16 lights, 157 ns): up to 2x the estimate; --max-render-s cancels what
    // runs over.
    // A medium that varies voxel to voxel and is dense in each (sigma_t x voxel 1 or more):
    // flights end inside a voxel and shadow rays sum voxel by voxel, each starting a walk of
    // its bricks. Measured (2026-12-07, 24^2 px, 16 voxels, paths of max_depth 1024, a 2-core
    // CPU, per vertex): noise at sigma_t x voxel 10 0.72 us with 1 light, 6.0 with 16; a one-voxel
    // grid shell at 1000 0.58 and 4.1 (no mesh; its mesh doubles the 1 light's); the same box
    // at a constant density 0.28: a unit 2.6x as long, a light as long as a vertex.
    const bool varies = scene.medium.density && !scene.medium.density->homogeneous();
    const double dense = varies ? std::clamp(m.mean_sigma_t * g.voxel, 0.0, 1.0) : 0;
    const double walk = 1 + 1.6 * dense, per_light = 0.6 + 0.4 * dense;
    // A dielectric's boundary refracts and reflects: Fresnel at every crossing, the flights
    // it reflects, and its shadow rays' exits, about doubling a vertex (the mesh bounds an
    // index-matched medium too, by default, and that is in the constant). Measured (2026-12-07,
    // bench/budget-survey.sh's dielectric scenes at 96^2 px, 32 voxels, 64 spp, the multiple
    // term): 1.9-4.0x the estimate without F_dr's events and this factor, 0.61-1.23x with them,
    // where the index-matched scenes took 0.53-0.82x.
    const double boundary = eta != 1 ? 2 : 1;
    double units = covered * s.spp * (1 + events) * (1 + per_light * lights) * bricks * blocker *
                   walk * boundary;
    double seconds = units * 70e-9 + (px - covered) * s.spp * 0.2e-6;
    std::string what = std::to_string(int(covered)) + " covered px x " + std::to_string(s.spp) +
                       " spp x " + short_number(1 + events) + " vertices x " +
                       std::to_string(int(lights)) + " lights";
    // max_seconds stops the passes: past it at most one sample's time, and never before three
    // samples.
    const double per = seconds / s.spp;
    const double until = std::max(s.max_seconds + per, std::min(s.spp, 3) * per);
    const bool stopped = s.max_seconds > 0 && seconds > until;
    if (stopped) {
      seconds = until;
      what += ", stopped at max_seconds " + short_number(s.max_seconds) + " s";
    }
    frame.time(stopped ? "settings.max_seconds" : "settings.spp", seconds, what);
  }
  upload.peak_of(frame);
  return upload.finish("reference");
}

}  // namespace scatter
