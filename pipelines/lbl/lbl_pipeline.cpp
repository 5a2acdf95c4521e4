#include "pipelines/lbl/lbl_pipeline.hpp"

#include <cmath>

#include "bake/cache.hpp"
#include "core/errors.hpp"
#include "pipelines/asset_key.hpp"
#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/common/stage_clock.hpp"
#include "pipelines/lbl/escape.hpp"
#include "pipelines/lbl/interleave.hpp"
#include "pipelines/lbl/light_rays.hpp"
#include "pipelines/lbl/second.hpp"

namespace scatter {
namespace {

// What the material volume and the lattice depend on: the asset, its medium, the grid, and the
// settings that shape them (not the lights, not the camera).
std::string material_key(const Scene& scene, const LblSettings& s) {
  BakeKey k = asset_key(scene);
  k.add("g", scene.medium.g).add("ior", scene.medium.ior);
  lbl_settings().add_to(k, s, Shapes::What::Kept, "material");
  return k.hex();
}

std::string light_key(const Scene& scene, const LblSettings& s) {
  BakeKey k;
  for (const Light& l : scene.lights) {
    k.add("type", double(int(l.type))).add("intensity", l.intensity);
    k.add("inner", l.inner_deg).add("outer", l.outer_deg);
    for (int c = 0; c < 3; ++c)
      k.add("position", l.position[c]).add("direction", l.direction[c]).add("color", l.color[c]);
  }
  lbl_settings().add_to(k, s, Shapes::What::Kept, "lights");
  return k.hex();
}

std::string diffusion_key(const LblSettings& s) {
  BakeKey k;
  lbl_settings().add_to(k, s, Shapes::What::Kept, "diffusion");
  return k.hex();
}

// A scattered photon's chance to scatter again somewhere in the volume, at most.
double second_scatter_bound(double max_sigma_s, double longest_side) {
  return -std::expm1(-max_sigma_s * longest_side);
}

// The lattice's state is the largest buffer: refuse, before voxelizing, a grid whose state the
// device cannot allocate (the grid's sides estimated from the mesh's bounds).
void check_lattice_size(const Scene& scene, const LblSettings& s, int margin, uint64_t max_alloc) {
  Aabb box;
  for (const Vec3& p : scene.mesh->positions) box.add(p);
  Vec3 size = box.size();
  double longest = std::max({size.x, size.y, size.z});
  if (!(longest > 0)) return;
  double nodes = 1;
  for (int a = 0; a < 3; ++a)
    nodes *= std::ceil(size[a] / longest * scene.voxels) + 2 * margin + s.block;
  double bytes = 3.0 * s.directions * nodes * sizeof(float);
  if (bytes > double(max_alloc))
    throw ValidationError("voxels",
                          "the lbl lattice would need " + std::to_string(long(bytes / (1 << 20))) +
                              " MiB per state buffer, more than the device's " +
                              std::to_string(long(max_alloc >> 20)) + " MiB: use fewer voxels" +
                              (s.directions == 18 ? " or 6 directions" : ""));
}

}  // namespace

namespace lbl {

struct State {
  std::string material, lights, diffusion;      // keys of what is loaded
  std::shared_ptr<const DensityField> density;  // keeps the keyed address alive
  Volume volume;
  ClVolume device;
  std::unique_ptr<Lattice> lattice;
  cl::Buffer deposit;  // single scattering of the light rays (the single term)
  cl::Buffer source;   // the lattice's source: the deposit, or with g != 0 the scaled beam's
  cl::Buffer flow;     // with g != 0: the deposit's direction summed over channels (3 per voxel,
                       // the view's phase), then the forward-scattered light's scattering (3)
  cl::Buffer lattice_flux;    // flux_phase: the lattice's light direction m (3 per voxel), made
                              // when first used
  bool flux_current = false;  // lattice_flux is the last diffusion's
  std::unique_ptr<SecondScatter> gather;  // setting second: its gather, made when first used
  cl::Buffer second;         // setting second: the light's second scattering (3 per voxel)
  cl::Buffer emission;       // then the multiple term's emission, irr + second / (1 - g)
  bool with_second = false;  // the last diffusion carried the third and later events
  double max_sigma_s = 0;
  bool diffused = false;  // the lattice has converged for the loaded deposit and settings
};

}  // namespace lbl

namespace {

// The view scatters the lattice's light with the phase's first moment about its direction
// (setting flux_phase; the 6-direction lattice's flux only).
bool uses_flux_phase(const Scene& scene, const LblSettings& s) {
  return s.flux_phase && scene.medium.g != 0 && s.directions == 6;
}

// The lattice starts from the light's exactly computed second scattering (setting second; the
// 6-direction lattice, not interleaved with the march).
bool uses_second(const LblSettings& s) {
  return s.second && s.directions == 6 && s.interleave == 0;
}

// Which stages a frame runs, from the scene, the request and what the last frame left.
struct Decision {
  bool material = true, march = true, diffuse = true, multiple = true, single = true;
  bool tiny = false, bend = false;
  double bound = 1;
  std::string bound_note;
};

Decision decide(const lbl::State* state, const Scene& scene, const RenderRequest& request,
                const LblSettings& s) {
  Decision d;
  d.material = !state || state->material != material_key(scene, s);
  d.march = d.material || state->lights != light_key(scene, s);
  d.single = request.terms != Terms::Multiple;
  d.multiple = request.terms != Terms::Single;
  d.bend = scene.medium.ior != 1.0;
  if (!d.material) {
    const lbl::Volume& v = state->volume;
    d.bound = second_scatter_bound(state->max_sigma_s, std::max({v.nx, v.ny, v.nz}) * v.voxel);
    d.bend = !v.constant_n;
  } else {
    // Before the volume exists: the medium's coefficients at density 1 over the mesh's extent.
    Aabb box;
    for (const Vec3& p : scene.mesh->positions) box.add(p);
    Vec3 size = box.size();
    double ms = std::max({scene.medium.sigma_s.x, scene.medium.sigma_s.y, scene.medium.sigma_s.z});
    d.bound = second_scatter_bound(ms, std::max({size.x, size.y, size.z}));
    d.bound_note = " (estimated at density 1)";
  }
  d.tiny = d.bound < s.skip_multiple;
  d.diffuse = d.multiple && !d.tiny &&
              (d.march || !state->diffused || state->diffusion != diffusion_key(s));
  return d;
}

StagePlan diffuse_stage(const Decision& d, const LblSettings& s) {
  std::string why;
  if (!d.multiple)
    why = "the single term needs no diffusion";
  else if (d.tiny)
    why = "a scattered photon scatters again with chance at most " + short_number(d.bound) +
          d.bound_note + " < skip_multiple " + short_number(s.skip_multiple) +
          ": multiple term taken as 0";
  else if (!d.diffuse)
    why = "camera-only change: converged irradiance kept";
  else
    why = std::string(s.blocked ? "blocks of " + std::to_string(s.block) + "^3, " +
                                      std::to_string(s.inner) + " steps per launch"
                                : "global lattice") +
          ", " + std::to_string(s.directions) + " directions + rest, until the change is under " +
          short_number(s.tolerance) + " (at most " + std::to_string(s.max_steps) + " steps)" +
          (!d.material && s.warm ? ", warm start from the last state" : "") +
          (uses_second(s)
               ? "; from the light's second scattering, gathered over " +
                     std::to_string(lbl::kSecondDirections) +
                     " directions through the scaled medium" +
                     (s.escape_stride > 1 ? " at one voxel in " + std::to_string(s.escape_stride) +
                                                " per axis as the escape correction"
                                          : std::string(" at every voxel")) +
                     " (the lattice carries the third and later events)"
               : std::string());
  return {"diffuse", d.diffuse, why};
}

Plan make_plan(const Scene& scene, Terms terms, const LblSettings& s, const Decision& d) {
  Plan p{"lbl", terms, {}};
  p.stages.push_back(
      {"volume", d.material,
       d.material
           ? std::to_string(scene.voxels) + " voxels on the long side; n, grad n smoothed over " +
                 short_number(s.smooth) + " voxels" +
                 (s.escape && s.directions == 6
                      ? "; escape correction over 32 directions" +
                            (s.escape_stride > 1
                                 ? " at one voxel in " + std::to_string(s.escape_stride) +
                                       " per axis, log-trilinear between inside one medium" +
                                       (s.escape_far > 0
                                            ? ", rays at half resolution past " +
                                                  short_number(s.escape_far) + " voxels"
                                            : std::string())
                                 : std::string(" at every voxel"))
                      : "")
           : "material unchanged: volume kept"});
  std::string path = d.bend ? "bent by the ray equation, step " + short_number(s.step) + " voxels"
                            : "constant n: straight rays, exact voxel crossings (no gradient)";
  p.stages.push_back({"march", d.march,
                      d.march ? std::to_string(scene.lights.size()) + " lights, " +
                                    short_number(s.rays) + " rays per voxel width, " + path +
                                    "; deposits added by CAS atomics"
                              : "lights and material unchanged: deposit kept"});
  p.stages.push_back(diffuse_stage(d, s));
  if (s.measure)
    p.stages.push_back({"bandwidth", d.diffuse,
                        d.diffuse ? "16 more lattice steps and 16 copies of its state, timed"
                                  : "nothing diffused in this frame"});
  std::string gathers =
      d.single && d.multiple ? "deposit + lattice" : (d.single ? "the deposit" : "the lattice");
  std::string phase = scene.medium.g != 0
                          ? "; HG phase (g " + short_number(scene.medium.g) +
                                ") about the light's direction for the single term and the "
                                "forward-scattered light, the lattice's (delta-Eddington "
                                "scaled) light " +
                                (uses_flux_phase(scene, s)
                                     ? std::string("by the phase's first moment about its flux")
                                     : std::string("isotropic")) +
                                (s.scaled_view ? " and seen through the scaled medium" : "")
                          : "";
  p.stages.push_back(
      {"view", true,
       std::string(d.bend ? "eye rays refracted by grad n" : "straight eye rays (DDA)") +
           ", gathering " + gathers + phase});
  p.stages.push_back({"readback", true, "linear RGB to the host"});
  return p;
}

}  // namespace

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
  const Decision d = decide(state_.get(), scene, request, LblSettings::read(request.settings));
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
  return make_plan(scene, request.terms, s, decide(state_.get(), scene, request, s));
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
  Decision d = decide(state_.get(), scene, request, s);
  result.plan = make_plan(scene, request.terms, s, d);
  if (d.material) {
    auto next = std::make_unique<lbl::State>();
    int margin = 1 + static_cast<int>(std::ceil(3 * s.smooth));
    check_lattice_size(scene, s, margin, cl.info().max_alloc);
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
    next->material = material_key(scene, s);
    next->density = scene.medium.density;
    state_ = std::move(next);
    queue.finish();
    clock.stop("volume");
    // The skip test now reads the real volume.
    Decision built = decide(state_.get(), scene, request, s);
    d.tiny = built.tiny;
    d.bound = built.bound;
    d.bound_note.clear();
    d.diffuse = d.multiple && !d.tiny;
    plan_stage(result.plan, "diffuse") = diffuse_stage(d, s);
  }
  lbl::State& st = *state_;
  last_steps_ = 0;
  int interleaved_steps = 0;  // lattice steps run between march rounds
  if (d.march) {
    lbl::RaySet rays = lbl::light_rays(scene.lights, st.volume, s.rays, 4096);
    cl::Buffer ray_buf = upload(cl, rays.rays);
    const bool with_flow = scene.medium.g != 0;
    cl::Buffer* flow = with_flow ? &st.flow : nullptr;
    for (cl::Buffer* b : {&st.deposit, &st.source})
      queue.enqueueFillBuffer(*b, 0.f, 0, 3 * st.volume.count() * sizeof(float));
    if (with_flow) queue.enqueueFillBuffer(st.flow, 0.f, 0, 6 * st.volume.count() * sizeof(float));
    if (s.interleave > 0 && d.diffuse) {
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
    st.lights = light_key(scene, s);
    st.diffused = false;
    clock.stop("march");
  }
  if (d.diffuse) {
    if (!s.warm && interleaved_steps == 0) st.lattice->clear();
    st.with_second = uses_second(s);
    if (st.with_second) {
      const size_t bytes = 3 * st.volume.count() * sizeof(float);
      if (!st.gather) {
        st.gather = std::make_unique<lbl::SecondScatter>(cl, st.volume, st.device, scene.medium.g,
                                                         s.escape_stride, s.escape_far);
        st.second = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, bytes);
        st.emission = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, bytes);
      }
      st.gather->run(st.source, st.second, request.progress);
      queue.finish();
      clock.stop("second");
    }
    st.lattice->set_source(st.with_second ? st.second : st.source);
    lbl::Convergence c =
        st.lattice->converge(s.tolerance, s.max_steps, s.check_every, request.progress);
    if (st.with_second)
      lbl::add_second(cl, st.lattice->irradiance_buffer(), st.second, scene.medium.g,
                      st.volume.count(), st.emission);
    queue.finish();
    st.diffused = true;
    st.flux_current = false;
    st.diffusion = diffusion_key(s);
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
  const bool flux_phase = uses_flux_phase(scene, s) && w_multiple != 0;
  if (flux_phase && !st.flux_current) {
    if (!st.lattice_flux())
      st.lattice_flux =
          cl::Buffer(cl.context(), CL_MEM_READ_WRITE, 3 * st.volume.count() * sizeof(float));
    st.lattice->flux(st.lattice_flux);
    st.flux_current = true;
  }
  const lbl::ClVolume& v = st.device;
  gpu::set_args(k, v.origin, v.voxel, v.nx, v.ny, v.nz, v.sigma_t, v.n, v.grad, st.deposit,
                st.with_second ? st.emission : st.lattice->irradiance_buffer(), w_single,
                w_multiple, st.flow, float(scene.medium.g), scene.medium.g != 0 ? 1 : 0, v.sigma_s,
                float(s.scaled_view ? scene.medium.g : 0.0),
                flux_phase ? st.lattice_flux : st.deposit, float(flux_phase ? scene.medium.g : 0.0),
                camera, w, h, d.bend ? 1 : 0, float(s.step * st.volume.voxel), out);
  queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(w, h));
  queue.finish();
  clock.stop("view");
  result.image = Image(w, h);
  queue.enqueueReadBuffer(out, CL_TRUE, 0, floats * sizeof(float), result.image.rgb.data());
  clock.stop("readback");
  return result;
}

}  // namespace scatter
