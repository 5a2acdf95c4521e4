#include "pipelines/lbl/lbl_pipeline.hpp"

#include <cmath>

#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/common/stage_clock.hpp"
#include "pipelines/lbl/escape.hpp"
#include "pipelines/lbl/interleave.hpp"
#include "pipelines/lbl/lbl_frame.hpp"
#include "pipelines/lbl/light_rays.hpp"
#include "pipelines/lbl/second.hpp"

namespace scatter {

LblPipeline::LblPipeline(gpu::Gpu& gpu) : gpu_(gpu) {}
LblPipeline::~LblPipeline() = default;

// The surface term: the mesh's Blinn-Phong under the lights with shadow maps (the surface
// pipeline's, shadows on); the medium's terms (single, multiple, all) do not include it, as the
// reference's do not.
RenderRequest LblPipeline::surface_request(const RenderRequest& request) {
  if (!surface_) surface_ = std::make_unique<SurfacePipeline>(gpu_);
  RenderRequest r{Terms::Surface, {{"shadows", 1}}, request.progress};
  return r;
}

bool LblPipeline::keeps(const Scene& scene, const RenderRequest& request) const {
  if (request.terms == Terms::Surface || !state_) return false;
  const lbl::Decision d =
      lbl::decide(state_.get(), scene, request, LblSettings::read(request.settings));
  return !d.material && !d.march && !d.diffuse;
}

Plan LblPipeline::plan(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  LblSettings s = LblSettings::read(request.settings);
  if (request.terms == Terms::Surface) {
    RenderRequest r = surface_request(request);  // makes surface_ first
    Plan p = surface_->plan(scene, r);
    p.pipeline = name();
    return p;
  }
  return lbl::make_plan(scene, request.terms, s, lbl::decide(state_.get(), scene, request, s));
}

RenderResult LblPipeline::render(const Scene& scene, const RenderRequest& request) {
  RenderResult result;
  require_terms(*this, request.terms);
  LblSettings s = LblSettings::read(request.settings);
  if (request.terms == Terms::Surface) {
    RenderRequest r = surface_request(request);
    result = surface_->render(scene, r);
    result.plan.pipeline = name();
    return result;
  }
  StageClock clock(result.timings);
  gpu::ClContext& cl = gpu_.cl();
  auto& queue = cl.queue();
  lbl::Decision d = lbl::decide(state_.get(), scene, request, s);
  result.plan = lbl::make_plan(scene, request.terms, s, d);
  if (d.material) {
    auto next = std::make_unique<lbl::State>();
    int margin = 1 + static_cast<int>(std::ceil(3 * s.smooth));
    lbl::check_lattice_size(scene, s, margin, cl.info().max_alloc);
    VoxelGrid grid = voxelize(scene, {.resolution = scene.voxels, .margin = margin});
    next->volume = lbl::make_volume(grid, scene.medium.ior, s.smooth, s.blocked ? s.block : 1);
    next->device = lbl::upload_volume(cl, next->volume);
    for (float x : next->volume.sigma_s) next->max_sigma_s = std::max<double>(next->max_sigma_s, x);
    lbl::LatticeOptions o{
        .blocked = s.blocked, .block = s.block, .inner = s.inner, .directions = s.directions};
    lbl::LatticeCoefficients coefficients = lbl::lattice_coefficients(next->volume, scene.medium.g);
    if (s.escape && s.directions == 6)
      coefficients.emit = lbl::escape_factor(
          lbl::exact_escape(cl, next->volume, scene.medium.g, 32, s.escape_stride, s.escape_far),
          lbl::lattice_escape(coefficients));
    next->lattice = std::make_unique<lbl::Lattice>(cl, coefficients, o);
    next->deposit =
        cl::Buffer(cl.context(), CL_MEM_READ_WRITE, 3 * next->volume.count() * sizeof(float));
    next->source = scene.medium.g == 0 ? next->deposit
                                       : cl::Buffer(cl.context(), CL_MEM_READ_WRITE,
                                                    3 * next->volume.count() * sizeof(float));
    next->flow = scene.medium.g == 0 ? next->deposit
                                     : cl::Buffer(cl.context(), CL_MEM_READ_WRITE,
                                                  6 * next->volume.count() * sizeof(float));
    next->material = lbl::material_key(scene, s);
    next->density = scene.medium.density;
    state_ = std::move(next);
    queue.finish();
    clock.stop("volume");
    // The skip test now reads the real volume.
    lbl::Decision built = lbl::decide(state_.get(), scene, request, s);
    d.tiny = built.tiny;
    d.bound = built.bound;
    d.bound_note.clear();
    d.diffuse = d.multiple && !d.tiny;
    d.gather = d.diffuse && lbl::uses_second(s);
    plan_stage(result.plan, "diffuse") = lbl::diffuse_stage(d, s);
  }
  lbl::State& st = *state_;
  last_steps_ = 0;
  int interleaved_steps = 0;  // lattice steps run between march rounds
  if (d.march) {
    const bool with_flow = scene.medium.g != 0;
    const int lobes = lbl::light_lobes(scene, s);
    lbl::RaySet rays;  // all the lights' (with lobes, each light's in turn below)
    cl::Buffer ray_buf;
    if (lobes == 1) {
      rays = lbl::light_rays(scene.lights, st.volume, s.rays, 4096);
      ray_buf = upload(cl, rays.rays);
    }
    cl::Buffer* flow = with_flow ? &st.flow : nullptr;
    // Until the march finishes the deposit is not the lights': a march that throws (an OpenCL
    // error) leaves a later frame marching again rather than reading a half-written deposit.
    st.lights.clear();
    st.diffused = st.second_current = false;
    st.lobes = 1;
    for (cl::Buffer* b : {&st.deposit, &st.source})
      queue.enqueueFillBuffer(*b, 0.f, 0, 3 * st.volume.count() * sizeof(float));
    if (with_flow) queue.enqueueFillBuffer(st.flow, 0.f, 0, 6 * st.volume.count() * sizeof(float));
    if (lobes > 1) {
      // Each light (or group of lights, light_groups) marched alone, its deposit and flow copied
      // out (the lattice's source, which only the diffusion reads, summed over them as before).
      const size_t bytes = 3 * st.volume.count() * sizeof(float);
      if (!st.lobe_deposit() || st.lobe_deposit.getInfo<CL_MEM_SIZE>() != lobes * bytes) {
        st.lobe_deposit = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, lobes * bytes);
        st.lobe_flow = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, 2 * lobes * bytes);
      }
      const std::vector<std::vector<int>> groups = lbl::light_groups(scene, lobes);
      for (int i = 0; i < lobes; ++i) {
        std::vector<Light> group;
        for (int l : groups[size_t(i)]) group.push_back(scene.lights[size_t(l)]);
        rays = lbl::light_rays(group, st.volume, s.rays, 4096);
        ray_buf = upload(cl, rays.rays);
        if (i > 0) {
          queue.enqueueFillBuffer(st.deposit, 0.f, 0, bytes);
          queue.enqueueFillBuffer(st.flow, 0.f, 0, 2 * bytes);
        }
        lbl::march(cl, st.device, ray_buf, rays.count(), d.bend, s.step * st.volume.voxel, s.cutoff,
                   scene.medium.g, st.deposit, st.source, flow);
        queue.enqueueCopyBuffer(st.deposit, st.lobe_deposit, 0, i * bytes, bytes);
        queue.enqueueCopyBuffer(st.flow, st.lobe_flow, 0, 2 * i * bytes, 2 * bytes);
        queue.finish();  // before ray_buf is replaced
      }
    } else if (s.interleave > 0 && d.diffuse) {
      if (!s.warm) st.lattice->clear();
      int per_round = std::max(1, static_cast<int>(std::lround(s.interleave * s.step)));
      lbl::InterleaveResult ir = lbl::march_interleaved(
          cl, st.device, ray_buf, rays.count(), d.bend, s.step * st.volume.voxel, s.cutoff,
          scene.medium.g, st.deposit, st.source, *st.lattice, s.interleave, per_round, flow);
      interleaved_steps = ir.lattice_steps;
      plan_stage(result.plan, "march").reason += "; interleaved: " + std::to_string(ir.rounds) +
                                                 " rounds of " + std::to_string(s.interleave) +
                                                 " steps, each followed by " +
                                                 std::to_string(per_round) + " lattice steps";
    } else {
      lbl::march(cl, st.device, ray_buf, rays.count(), d.bend, s.step * st.volume.voxel, s.cutoff,
                 scene.medium.g, st.deposit, st.source, flow);
    }
    queue.finish();
    st.lobes = lobes;
    st.lights = lbl::light_key(scene, s);
    st.diffused = st.second_current = false;
    clock.stop("march");
  }
  if (d.diffuse) {
    st.diffused = st.with_second = false;  // until this diffusion finishes (it may be cancelled)
    if (!s.warm && interleaved_steps == 0) st.lattice->clear();
    const bool with_second = lbl::uses_second(s);
    if (d.gather) {
      const size_t bytes = 3 * st.volume.count() * sizeof(float);
      if (!st.gather) {
        st.gather = std::make_unique<lbl::SecondScatter>(cl, st.volume, st.device, scene.medium.g,
                                                         s.escape_stride, s.escape_far);
        st.second = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, bytes);
        st.second_dir = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, bytes);
      }
      if (s.gathers > 1 && !st.last()) st.last = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, bytes);
      st.second_current = false;
      // The gather reports the first half of the progress, the lattice's steps the second.
      std::function<void(double)> progress;
      if (request.progress) progress = [&](double f) { request.progress(0.5 * f); };
      st.gather->run(st.source, st.second, st.second_dir, progress);
      // The later orders: each from the last (st.second holds the second until the first of
      // them has read it), summed into st.second.
      for (int k = 2; k <= s.gathers; ++k)
        st.gather->next_order(k == 2 ? st.second : st.last, st.last, st.second);
      queue.finish();
      st.second_current = true;
      st.second_gathers = s.gathers;
      clock.stop("second");
    }
    st.lattice->set_source(!with_second ? st.source : s.gathers > 1 ? st.last : st.second);
    std::function<void(double)> progress = request.progress;
    if (with_second && request.progress)
      progress = [&](double f) { request.progress(0.5 + 0.5 * f); };
    lbl::Convergence c = st.lattice->converge(s.tolerance, s.max_steps, s.check_every, progress);
    queue.finish();
    st.diffused = true;
    st.with_second = with_second;
    st.flux_current = false;
    st.diffusion = lbl::diffusion_key(s);
    last_steps_ = interleaved_steps + c.steps;
    plan_stage(result.plan, "diffuse").reason +=
        c.converged ? "; converged in " + std::to_string(c.steps) + " steps" +
                          (interleaved_steps ? " after the march" : "")
                    : "; stopped at the step bound after " + std::to_string(c.steps) +
                          " steps (change " + short_number(c.change) + ")";
    clock.stop("diffuse");
    if (s.measure) {
      double step_ms = st.lattice->time_steps(16), copy_ms = st.lattice->time_copy(16);
      plan_stage(result.plan, "bandwidth").reason =
          "lattice step " + short_number(step_ms) +
          " ms = " + short_number(st.lattice->step_bytes() / step_ms / 1e6) +
          " GB/s; STREAM-like copy " + short_number(copy_ms) +
          " ms = " + short_number(st.lattice->copy_bytes() / copy_ms / 1e6) + " GB/s";
      clock.stop("bandwidth");
    }
  }
  const int w = scene.width, h = scene.height;
  const size_t floats = size_t(w) * h * 3;
  cl::Buffer camera = upload(cl, pack_camera(scene.camera, w, h));
  cl::Buffer out(cl.context(), CL_MEM_WRITE_ONLY, floats * sizeof(float));
  cl::Kernel k(cl.program(with_cl_library({"kernels/lbl/common.cl", "kernels/lbl/view.cl"})),
               "view_pass");
  const float w_single = d.single ? 1.f : 0.f, w_multiple = d.multiple && !d.tiny ? 1.f : 0.f;
  const bool flux_phase = lbl::uses_flux_phase(scene, s) && w_multiple != 0;
  if (flux_phase && !st.flux_current) {
    if (!st.lattice_flux())
      st.lattice_flux =
          cl::Buffer(cl.context(), CL_MEM_READ_WRITE, 3 * st.volume.count() * sizeof(float));
    st.lattice->flux(st.lattice_flux);
    st.flux_current = true;
  }
  const lbl::ClVolume& v = st.device;
  gpu::set_args(
      k, v.origin, v.voxel, v.nx, v.ny, v.nz, v.sigma_t, v.n, v.grad,
      st.lobes > 1 ? st.lobe_deposit : st.deposit, st.lattice->irradiance_buffer(), w_single,
      w_multiple, st.lobes > 1 ? st.lobe_flow : st.flow, float(scene.medium.g),
      scene.medium.g != 0 ? 1 : 0, st.lobes, v.sigma_s, float(s.scaled_view ? scene.medium.g : 0.0),
      flux_phase ? st.lattice_flux : st.deposit, float(flux_phase ? scene.medium.g : 0.0),
      st.with_second ? st.second : st.deposit, st.with_second ? st.second_dir : st.deposit,
      float(st.with_second ? 1 / (1 - scene.medium.g) : 0.0),
      float(st.with_second && s.second_phase ? scene.medium.g : 0.0),
      lbl::uses_tms(scene, s) ? 1 : 0, camera, w, h, d.bend ? 1 : 0,
      float(s.step * st.volume.voxel), out);
  queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(w, h));
  queue.finish();
  clock.stop("view");
  result.image = Image(w, h);
  queue.enqueueReadBuffer(out, CL_TRUE, 0, floats * sizeof(float), result.image.rgb.data());
  clock.stop("readback");
  return result;
}

}  // namespace scatter
