#include "pipelines/reference/reference_pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/errors.hpp"
#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/common/stage_clock.hpp"
#include "pipelines/metrics.hpp"
#include "pipelines/reference/cell_triangles.hpp"
#include "pipelines/reference/convex.hpp"
#include "pipelines/reference/exit_maps.hpp"
#include "pipelines/reference/inside_grid.hpp"
#include "scene/bvh.hpp"

namespace scatter {
namespace {

const std::vector<std::string> kProgram = with_cl_library({"kernels/reference/boundary.cl"});

std::vector<std::string> program(const char* file) {
  auto p = kProgram;
  p.push_back(file);
  return p;
}

// The batches a standard error is taken from alone at the least (31 degrees of freedom: with 12
// a pixel's estimate was often several times too small where rare events carry the variance);
// from 4 to 31 batches the larger of it and the samples' own variance (which usually overstates
// a stratified mean's error); below 4 the samples' own.
constexpr int kMinBatches = 32, kFewBatches = 4;

// The kernel's sums (kernels/reference/path.cl), every sample carrying the three channels:
// sum_sq and batch_sq hold squares times sq_scale; part is the open batch's sum.
struct Sums {
  std::vector<float> sum, sum_sq, part, batch_sq;
};

// Mean and standard error of the mean of `spp` samples in batches of `batch`. With k
// complete batches of sums S_j, var(S) is their sample variance and the mean's variance
// var(S) / (batch spp): the batches are independent, the samples within one are not.
void finish_estimate(const Sums& s, int spp, int batch, double sq_scale, Image& mean,
                     Image& std_error) {
  const double n = spp;
  const int k = spp / batch;
  for (size_t i = 0; i < s.sum.size(); ++i) {
    double m = s.sum[i] / n;
    double var = std::max(0.0, s.sum_sq[i] / sq_scale / n - m * m) * n / std::max(1.0, n - 1);
    double var_mean = var / n;
    if (batch > 1 && k >= kFewBatches) {
      double total = s.sum[i] - s.part[i], mb = total / k;  // the complete batches' mean sum
      double var_s = std::max(0.0, s.batch_sq[i] / sq_scale / k - mb * mb) * k / (k - 1.0);
      double batches = var_s / (double(batch) * n);
      var_mean = k >= kMinBatches ? batches : std::max(batches, var_mean);
    }
    mean.rgb[i] = static_cast<float>(m);
    std_error.rgb[i] = static_cast<float>(std::sqrt(var_mean));
  }
}

// The inverse of the largest power (intensity or irradiance times colour) of the lights: the
// kernel keeps squared radiance in these units, which float32 holds for every power a scene may
// give (kernels/reference/path.cl).
double square_scale(const Scene& scene) {
  double power = 0;
  for (const Light& l : scene.lights)
    power = std::max(
        {power, l.intensity * l.color.x, l.intensity * l.color.y, l.intensity * l.color.z});
  return power > 0 ? std::clamp(1 / power, 1e-30, 1e30) : 1;
}

// A read-only buffer of `v` (one element when empty: OpenCL has no empty buffers).
cl::Buffer upload_ints(gpu::ClContext& cl, const std::vector<int32_t>& v) {
  cl::Buffer b(cl.context(), CL_MEM_READ_ONLY, std::max<size_t>(v.size(), 1) * sizeof(int32_t));
  if (!v.empty())
    cl.queue().enqueueWriteBuffer(b, CL_TRUE, 0, v.size() * sizeof(int32_t), v.data());
  return b;
}

}  // namespace

int batch_for(int spp) {
  int b = 1;
  while (b < 16 && 2 * b * 32 <= spp) b *= 2;
  return b;
}

Plan ReferencePipeline::plan(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  return describe(scene, request.terms, ReferenceSettings::read(request.settings));
}

Plan ReferencePipeline::describe(const Scene& scene, Terms terms,
                                 const ReferenceSettings& s) const {
  Plan p{name(), terms, {}};
  p.stages.push_back({"voxelize", true,
                      std::to_string(scene.voxels) + " voxels on the long side" +
                          (s.voxel_boundary ? "" : ": the density inside the mesh, per voxel")});
  const std::string bounds = s.voxel_boundary ? "" : ", which bounds the medium,";
  if (scene.medium.ior != 1.0)
    p.stages.push_back({"boundary", true,
                        "ior " + std::to_string(scene.medium.ior) + ": BVH over the mesh" + bounds +
                            " for Fresnel and refraction; shadow rays are not refracted "
                            "(approximate)"});
  else if (!s.voxel_boundary)
    p.stages.push_back({"boundary", true,
                        "BVH over the mesh, which bounds the medium; index matched (ior 1): no "
                        "reflection or refraction"});
  else
    p.stages.push_back({"boundary", false,
                        "voxel_boundary=1 and index matched (ior 1): the voxelized medium alone"});
  if (p.stages.back().run && !s.marches(terms)) {
    const char* queries[] = {
        "; the path tracer's mesh queries traverse the BVH (cells=0)",
        "; the path tracer's mesh queries walk per-voxel triangle lists with the voxel DDA "
        "(cells=1)",
        "; the path tracer's mesh queries walk per-voxel triangle lists with the voxel DDA where "
        "the lists are short on a large mesh, else traverse the BVH (cells=2)"};
    p.stages.back().reason += queries[std::clamp(s.cells, 0, 2)];
  }
  p.stages.push_back({"upload", true, "medium, per-brick majorants (8^3 voxels), lights, camera"});
  if (s.marches(terms)) {
    p.stages.push_back(
        {"march", true,
         "deterministic single scattering, step " + std::to_string(s.step) + " voxels"});
    p.stages.push_back(
        {"trace", false, "the single term is marched, not sampled (mc=1 samples it)"});
  } else {
    p.stages.push_back({"march", false, "Monte Carlo estimates this term"});
    p.stages.push_back({"trace", true,
                        std::to_string(s.spp) + " samples per pixel, " +
                            (terms == Terms::Single ? "first vertex only" : "all orders") +
                            (s.max_seconds > 0 ? ", or as many as " + short_number(s.max_seconds) +
                                                     " s allow (max_seconds)"
                                               : "")});
  }
  p.stages.push_back({"readback", true, "mean and standard error"});
  return p;
}

RenderResult ReferencePipeline::render(const Scene& scene, const RenderRequest& request) {
  RenderResult result;
  require_terms(*this, request.terms);
  const ReferenceSettings s = ReferenceSettings::read(request.settings);  // once a frame
  result.plan = describe(scene, request.terms, s);
  StageClock clock(result.timings);
  VoxelGrid grid = voxelize(scene, {.resolution = scene.voxels});
  const bool dielectric = scene.medium.ior != 1.0;
  // The mesh bounds the medium (kernels/reference/boundary.cl), index matched or not, unless
  // voxel_boundary asks for the voxelized medium alone (then only a dielectric needs the mesh).
  const bool mesh_bounds = !s.voxel_boundary;
  if (mesh_bounds) restrict_to_mesh(grid);
  clock.stop("voxelize");
  FlatBvh bvh;
  CellTriangles cells;
  if (mesh_bounds || dielectric) {
    bvh = build_bvh(*scene.mesh);
    if (s.builds_cell_lists(bvh.triangles.size() / 12, request.terms)) {
      cells = cell_triangles(grid, bvh);
      if (s.cells == 2 && !uses_cell_lists(cells, bvh)) cells = {};
    }
    clock.stop("boundary");
  }
  if (s.cells == 2 && (mesh_bounds || dielectric) && !s.marches(request.terms))
    plan_stage(result.plan, "boundary").reason +=
        cells.triangles.empty() ? ": the BVH" : ": the lists";

  gpu::ClContext& cl = gpu_.cl();
  cl::Buffer bvh_bounds = upload(cl, bvh.bounds);
  cl::Buffer bvh_tris = upload(cl, bvh.triangles);
  cl::Buffer bvh_links = upload_ints(cl, bvh.links);
  cl::Buffer cell_first = upload_ints(cl, cells.first);
  cl::Buffer cell_tris = upload_ints(cl, cells.triangles);
  cells.skip.resize(std::max<size_t>(cells.skip.size(), 1));
  cl::Buffer cell_skip(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, cells.skip.size(),
                       cells.skip.data());
  const float ior = static_cast<float>(scene.medium.ior);
  // How far each voxel is from the boundary, and whether a path once out stays out.
  std::vector<uint8_t> interior =
      mesh_bounds ? interior_depth(grid) : std::vector<uint8_t>(grid.count(), 0);
  cl::Buffer interior_buf(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, interior.size(),
                          interior.data());
  const int convex = (mesh_bounds || dielectric) && is_convex(*scene.mesh);
  ExitMaps exits;
  if (convex && s.exit_maps && !s.marches(request.terms)) exits = exit_maps(bvh, scene.lights);
  if (exits.header.empty()) exits.header.assign(kExitMapFloats, 0.f);
  cl::Buffer exit_header = upload(cl, exits.header);
  cl::Buffer exit_first = upload_ints(cl, exits.first);
  cl::Buffer exit_tris = upload_ints(cl, exits.triangles);
  if (!exits.empty())
    plan_stage(result.plan, "boundary").reason +=
        "; the mesh is convex: shadow rays find their exit in maps of the light-facing "
        "triangles (exit_maps) towards " +
        std::to_string(exits.lights()) + " of " + std::to_string(scene.lights.size()) + " lights";
  ClMedium medium = upload_medium(cl, grid);
  // Bricks of one coefficient need no voxel walk (pipelines/reference/inside_grid.hpp).
  std::vector<int32_t> uniform = uniform_bricks(grid, medium.bricks.brick, mesh_bounds);
  // One coefficient everywhere a segment inside the mesh goes: no walks at all (only where the
  // mesh bounds the medium, so that every tracked segment lies inside it).
  const int32_t homogeneous = mesh_bounds && s.homogeneous && !s.marches(request.terms)
                                  ? homogeneous_voxel(grid, uniform)
                                  : -1;
  if (homogeneous >= 0)
    plan_stage(result.plan, "upload").reason +=
        "; one coefficient inside the mesh: the path tracer's flights and optical depths take no "
        "walk (homogeneous)";
  cl::Buffer uniform_buf(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                         uniform.size() * sizeof(int32_t), uniform.data());
  cl::Buffer lights = upload(cl, pack_lights(scene.lights));
  cl::Buffer camera = upload(cl, pack_camera(scene.camera, scene.width, scene.height));
  const int w = scene.width, h = scene.height;
  const size_t floats = size_t(w) * h * 3;
  cl::NDRange global(w, h);
  auto& queue = cl.queue();
  queue.finish();
  clock.stop("upload");

  result.image = Image(w, h);
  const int light_count = static_cast<int>(scene.lights.size());
  const float g = static_cast<float>(scene.medium.g);
  if (s.marches(request.terms)) {
    // kernels/reference/single_march.cl keeps two floats per light for the sub-steps' ends.
    if (scene.lights.size() > 16)
      throw ValidationError("scene.lights", "the reference marcher takes at most 16 lights");
    cl::Buffer out(cl.context(), CL_MEM_WRITE_ONLY, floats * sizeof(float));
    cl::Kernel k(cl.program(program("kernels/reference/single_march.cl")), "single_march");
    gpu::set_args(k, medium.origin, medium.voxel, medium.nx, medium.ny, medium.nz, medium.sigma_s,
                  medium.sigma_t, lights, light_count, g, camera, w, h, float(s.step), ior,
                  int(mesh_bounds || dielectric), bvh_bounds, bvh_links, bvh_tris, out);
    queue.enqueueNDRangeKernel(k, cl::NullRange, global);
    queue.finish();
    clock.stop("march");
    queue.enqueueReadBuffer(out, CL_TRUE, 0, floats * sizeof(float), result.image.rgb.data());
    clock.stop("readback");
    return result;
  }

  std::vector<float> zeros(floats, 0.f);
  cl::Buffer sum(cl.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, floats * sizeof(float),
                 zeros.data());
  cl::Buffer sum_sq(cl.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, floats * sizeof(float),
                    zeros.data());
  cl::Buffer part(cl.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, floats * sizeof(float),
                  zeros.data());
  cl::Buffer batch_sq(cl.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                      floats * sizeof(float), zeros.data());
  cl::Kernel k(cl.program(program("kernels/reference/path.cl")), "path_trace");
  int terms = request.terms == Terms::Single ? 1 : (request.terms == Terms::Multiple ? 2 : 3);
  // Progressive passes of a few samples keep each launch short and let callers see progress.
  // With a budget (max_error), spp is the expected count: the passes go on until the relative
  // standard error is under the budget with its margin (RenderRequest::kBudgetMargin), checked
  // every twelfth of the samples so far (whole rounds of three), up to 8x spp, or, for a budget the
  // caller asked for (not auto's soft one), as many more as the standard error measured then says
  // the budget needs (up to 64x). With max_seconds, or a time limit (9/10 of it, less what came
  // before the trace), no pass starts once not even half a sample fits in what is left, and a pass
  // takes only the samples expected to fit (the first pass one sample, to time it).
  const int per_pass = std::min(s.spp, 4);
  const double target = RenderRequest::kBudgetMargin * request.max_error.value_or(0);
  int cap = request.max_error ? std::min(8 * s.spp, 1 << 20) : s.spp;
  const int most = request.max_error && !request.soft_budget ? std::min(64 * s.spp, 1 << 20) : cap;
  const double sq_scale = square_scale(scene);
  const int batch = s.batch > 0 ? s.batch : batch_for(s.spp);
  Sums host{std::vector<float>(floats), std::vector<float>(floats), std::vector<float>(floats),
            std::vector<float>(floats)};
  result.std_error = Image(w, h);
  // The relative standard error, and what the passes compare with the target: the error one
  // image reaches scatters about it (its square by error_scatter: a few noisy pixels, on a small
  // image or where rare paths carry the light, make it wide), so with a budget the standard error
  // is taken two of those deviations up (at 24 x 24 pixels on a dielectric sphere lit from the
  // side, 2 seeds in 10 landed over the budget when the standard error alone met its margin).
  double scatter = 0;
  auto noise_now = [&](int spp) {
    queue.enqueueReadBuffer(sum, CL_TRUE, 0, floats * sizeof(float), host.sum.data());
    queue.enqueueReadBuffer(sum_sq, CL_TRUE, 0, floats * sizeof(float), host.sum_sq.data());
    queue.enqueueReadBuffer(part, CL_TRUE, 0, floats * sizeof(float), host.part.data());
    queue.enqueueReadBuffer(batch_sq, CL_TRUE, 0, floats * sizeof(float), host.batch_sq.data());
    finish_estimate(host, spp, batch, sq_scale, result.image, *result.std_error);
    scatter = error_scatter(*result.std_error);
    return relative_norm(*result.std_error, result.image);
  };
  auto with_scatter = [&](double noise) { return noise * std::sqrt(1 + 2 * scatter); };
  const auto trace_start = std::chrono::steady_clock::now();
  auto traced_seconds = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - trace_start).count();
  };
  // The trace's own time: max_seconds, and what the caller's time limit leaves.
  double trace_limit = s.max_seconds;
  bool by_time_limit = false;
  if (request.time_limit_s > 0) {
    // A tenth of the limit to spare, counted from the request's start (auto's earlier part, this
    // render's upload).
    const double before = std::chrono::duration<double>(trace_start - request.started).count();
    const double left = std::max(1e-3, 0.9 * request.time_limit_s - before);
    if (trace_limit <= 0 || left < trace_limit) {
      trace_limit = left;
      by_time_limit = true;
    }
  }
  int spp = 0, next_check = 12;
  bool out_of_time = false;
  double shown = 0;  // the progress reported so far (the cap may grow)
  std::optional<double> noise;
  for (int done = 0; done < cap; done += per_pass) {
    int n = std::min(per_pass, cap - done);
    if (trace_limit > 0) {
      // Time a sample, then take what fits; stop once not even half a sample does, but not
      // before three samples (spp's least: fewer give no standard error to speak of).
      const int least = std::min(3, cap);
      double used = traced_seconds(), per_sample = done > 0 ? used / done : 0;
      if (done >= least && used + 0.5 * per_sample >= trace_limit) {
        out_of_time = true;
        break;
      }
      int fit = done == 0 ? 1
                          : int(std::clamp((trace_limit - used) / std::max(per_sample, 1e-9),
                                           double(std::max(1, least - done)), double(n)));
      n = std::min(fit, per_pass - done % per_pass);  // passes still end on multiples of per_pass
    }
    gpu::set_args(k, medium.origin, medium.voxel, medium.nx, medium.ny, medium.nz,
                  medium.bricks.brick, medium.bricks.bx, medium.bricks.by, medium.bricks.bz,
                  medium.sigma_s, medium.sigma_t, medium.majorant, uniform_buf, homogeneous, lights,
                  light_count, g, camera, w, h, terms, n, done, s.seed, s.max_depth, ior,
                  int(mesh_bounds || dielectric), convex, interior_buf, bvh_bounds, bvh_links,
                  bvh_tris, int(!cells.triangles.empty()), cell_first, cell_tris, cell_skip,
                  int(!exits.empty()), exit_header, exit_first, exit_tris, batch, float(sq_scale),
                  sum, sum_sq, part, batch_sq);
    queue.enqueueNDRangeKernel(k, cl::NullRange, global);
    queue.finish();
    spp = done + n;
    done = spp - per_pass;  // the loop adds per_pass back
    if (request.max_error && ((spp >= next_check && spp % 12 == 0) || spp == cap)) {
      noise = noise_now(spp);
      if (with_scatter(*noise) <= target) break;
      next_check = spp + std::max(12, spp / 12 / 12 * 12);
      // What the standard error measured says the target needs, a tenth to spare.
      const double need = 1.1 * spp * std::pow(with_scatter(*noise) / target, 2);
      if (std::isfinite(need) && need > cap)
        cap = int(std::min<double>(most, std::ceil(need / 12) * 12));
    }
    if (request.progress) {
      shown = std::max(
          shown, std::min(1.0, std::max(double(spp) / cap,
                                        trace_limit > 0 ? traced_seconds() / trace_limit : 0.0)));
      request.progress(shown);
    }
  }
  clock.stop("trace");
  noise = noise_now(spp);
  result.error_estimate = noise;
  const std::string stopped_by =
      !out_of_time    ? ""
      : by_time_limit ? "the render's time limit (" + short_number(request.time_limit_s) + " s)"
                      : "max_seconds " + short_number(s.max_seconds) + " s";
  if (request.max_error) {
    std::string where = out_of_time ? "at " + stopped_by
                        : spp >= most
                            ? "at " + std::to_string(most / s.spp) + "x the expected samples" +
                                  (request.soft_budget ? " (the default budget's most)" : "")
                            : "at " + std::to_string(cap) + " samples, what its standard error " +
                                  "said the budget needs";
    plan_stage(result.plan, "trace").reason =
        std::to_string(spp) + " samples per pixel: relative standard error " +
        short_number(100 * *noise) + " %, " + short_number(100 * with_scatter(*noise)) +
        " % with the scatter of one image's error (its square's, " + short_number(100 * scatter) +
        " %, twice), " +
        (with_scatter(*noise) <= *request.max_error ? "under" : "still over, " + where + ",") +
        " the budget of " + short_number(100 * *request.max_error) + " % (aiming at " +
        short_number(100 * target) + " %)";
  } else if (out_of_time) {
    plan_stage(result.plan, "trace").reason =
        std::to_string(spp) + " of " + std::to_string(s.spp) + " samples per pixel, what " +
        stopped_by + " allowed: relative standard error " + short_number(100 * *noise) + " %";
  }
  clock.stop("readback");
  return result;
}

}  // namespace scatter
