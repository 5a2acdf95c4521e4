#include "pipelines/single/single_pipeline.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <string_view>

#include "bake/cache.hpp"
#include "core/errors.hpp"
#include "pipelines/asset_key.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/common/raster.hpp"
#include "pipelines/common/stage_clock.hpp"

namespace scatter {

namespace {

// Bump when the bake's results change, so old cache entries are not reused.
// 8: samples in progressive order; 9: sigma at least kMinSigmaVoxels; 10: splits from empty
// voxels and the shell, each piece's sigma_s from its own medium
constexpr const char* kSingleBakeVersion = "single-10";

}  // namespace

// The product's key, from the asset's identity (pipelines/asset_key.hpp) and the settings that
// shape the bake: known before anything is voxelized, so a live session's frame of the same asset
// skips the voxelization, and a bake job is named by what it will make.
std::string SinglePipeline::product_key(const Scene& scene, const SingleSettings& settings) {
  BakeKey key = asset_key(scene);
  key.add("pipeline", "single").add("version", kSingleBakeVersion).add("margin", kSingleGridMargin);
  single_settings().add_to(key, settings, Shapes::What::Bake);
  return key.hex();
}

namespace {

double median(std::vector<float> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

gpu::GlObject storage(const std::vector<float>& data) {
  auto b = gpu::GlObject::create(gpu::GlKind::Buffer);
  glNamedBufferStorage(b.get(),
                       static_cast<GLsizeiptr>(std::max<size_t>(data.size(), 1) * sizeof(float)),
                       data.empty() ? nullptr : data.data(), 0);
  return b;
}

}  // namespace

SinglePipeline::SinglePipeline(gpu::Gpu& gpu, BakeCache* cache) : gpu_(gpu), cache_(cache) {
  if (!cache_) {
    own_cache_ = std::make_unique<BakeCache>();
    cache_ = own_cache_.get();
  }
}

SinglePipeline::~SinglePipeline() {
  // GL names must be deleted with the context current.
  if (distance_program_ || positions_) gpu_.gl().make_current();
}

BakeResult SinglePipeline::bake(const Scene& scene, const RenderRequest& request,
                                const BakeProgress& progress) {
  SingleSettings s = SingleSettings::read(request.settings);
  return bake(scene, s, product_key(scene, s), progress);
}

BakeResult SinglePipeline::bake(const Scene& scene, const SingleSettings& s, const std::string& fp,
                                const BakeProgress& progress) {
  BakeResult r;
  r.needed = true;
  StageClock clock(r.timings);
  if (!current_.bake || current_.fingerprint != fp) {
    if (progress) progress("voxelize", 0);
    auto grid_ptr = std::make_shared<const VoxelGrid>(
        voxelize(scene, {.resolution = scene.voxels, .margin = kSingleGridMargin}));
    const VoxelGrid& grid = *grid_ptr;
    clock.stop("voxelize");
    const std::string& hex = fp;
    std::shared_ptr<const SingleBake> product;
    if (auto bytes = cache_->get(hex)) {
      try {
        product = std::make_shared<SingleBake>(SingleBake::deserialize(**bytes));
        r.cache_hit = true;
      } catch (const std::exception& e) {
        spdlog::warn("event=bake_product_unreadable key={} problem=\"{}\" outcome=rebake", hex,
                     e.what());
      }
    }
    if (!product) {
      auto made = std::make_shared<SingleBake>(bake_single(gpu_.cl(), grid, s.bake, progress));
      cache_->put(hex, made->serialize());
      product = std::move(made);
    }
    clock.stop(r.cache_hit ? "cache" : "bake");
    current_ = {fp, hex, std::move(product), scene.medium.density, grid_ptr, false, false};
    current_.sigma_median = median(current_.bake->sigma);
    std::vector<float> st;
    for (size_t v = 0; v < grid.count(); ++v) {
      float t = (grid.sigma_s[3 * v] + grid.sigma_a[3 * v] + grid.sigma_s[3 * v + 1] +
                 grid.sigma_a[3 * v + 1] + grid.sigma_s[3 * v + 2] + grid.sigma_a[3 * v + 2]) /
                3;
      if (t > 0) st.push_back(t);
    }
    current_.sigma_t_median = median(std::move(st));
  } else {
    r.cache_hit = true;
    clock.stop("cache");
  }
  const SingleBake& b = *current_.bake;
  r.key = current_.key;
  r.bake_timings = b.timings;
  r.stats = {{"samples", b.count - b.split},
             {"pieces", b.count},
             {"split", b.split},
             {"directions", b.params.directions},
             {"sh_coefficients", b.coefficients()},
             {"sh_of", b.params.sh_depth ? "optical depth" : "transmittance"},
             {"coverage_mean", b.coverage_mean},
             {"coverage_spread", b.coverage_spread},
             {"bytes", b.position.size() * 4 + b.sigma.size() * 4 + b.weight.size() * 4 +
                           b.sigma_s.size() * 4 + b.plane.size() * 4 + b.sh.size() * 4}};
  return r;
}

double near_pixels_per_unit(const Scene& scene) {
  Aabb box = scene.mesh->bounds();
  double reach = length(box.size()) / 2;
  double dist = std::max(length(box.center() - scene.camera.position) - reach, 0.25 * reach);
  return scene.height / 2.0 / (dist * std::tan(scene.camera.fov_deg * std::numbers::pi / 360));
}

void SinglePipeline::upload() {
  const SingleBake& b = *current_.bake;
  positions_ = storage(b.position);
  weights_ = storage(b.weight);
  sigma_s_ = storage(b.sigma_s);
  sh_ = storage(b.sh);
  sigmas_ = storage(b.sigma);
  planes_ = storage(b.plane.empty() ? std::vector<float>(size_t(std::max(b.count, 1)) * 4, 0.f)
                                    : b.plane);
  colors_ = gpu::GlObject::create(gpu::GlKind::Buffer);
  glNamedBufferStorage(colors_.get(),
                       static_cast<GLsizeiptr>(std::max(b.count, 1) * 4 * sizeof(float)), nullptr,
                       GL_MAP_READ_BIT | GL_DYNAMIC_STORAGE_BIT);
  // cuts_: three float4 a sample (the linear cut, the quadratic model's slope and curvature).
  for (auto [buffer, floats] :
       {std::pair{&shifts_, 4}, std::pair{&axes_, 4}, std::pair{&cuts_, 12}}) {
    *buffer = gpu::GlObject::create(gpu::GlKind::Buffer);
    glNamedBufferStorage(buffer->get(),
                         static_cast<GLsizeiptr>(std::max(b.count, 1) * floats * sizeof(float)),
                         nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
  reset_moves();
  current_.uploaded = true;
}

void SinglePipeline::reset_moves() {
  const SingleBake& b = *current_.bake;
  glClearNamedBufferData(shifts_.get(), GL_R32F, GL_RED, GL_FLOAT, nullptr);
  glClearNamedBufferData(cuts_.get(), GL_R32F, GL_RED, GL_FLOAT, nullptr);
  std::vector<float> axes(size_t(std::max(b.count, 1)) * 4, 0.f);
  for (int i = 0; i < b.count; ++i) std::fill_n(&axes[4 * size_t(i)], 3, b.sigma[i]);  // w: 0
  glNamedBufferSubData(axes_.get(), 0, static_cast<GLsizeiptr>(axes.size() * sizeof(float)),
                       axes.data());
  current_.moved = false;
}

std::vector<float> SinglePipeline::read_shaded() const {
  if (!colors_ || !current_.bake) return {};
  gpu_.gl().make_current();
  std::vector<float> out(size_t(current_.bake->count) * 4);
  glGetNamedBufferSubData(colors_.get(), 0, static_cast<GLsizeiptr>(out.size() * sizeof(float)),
                          out.data());
  return out;
}

std::pair<std::vector<float>, std::vector<float>> SinglePipeline::read_moves() const {
  if (!shifts_ || !current_.bake) return {};
  gpu_.gl().make_current();
  std::vector<float> shifts(size_t(current_.bake->count) * 4), axes(shifts.size());
  glGetNamedBufferSubData(shifts_.get(), 0, static_cast<GLsizeiptr>(shifts.size() * sizeof(float)),
                          shifts.data());
  glGetNamedBufferSubData(axes_.get(), 0, static_cast<GLsizeiptr>(axes.size() * sizeof(float)),
                          axes.data());
  return {shifts, axes};
}

RenderResult SinglePipeline::render(const Scene& scene, const RenderRequest& request) {
  RenderResult result;
  require_terms(*this, request.terms);
  const SingleSettings s = SingleSettings::read(request.settings);  // once a frame
  const std::string fp = product_key(scene, s);
  result.plan = make_plan(scene, request.terms, s, fp);
  // A bake inside a render reports to the render's progress, which may stop it (a cancel).
  BakeProgress progress;
  if (request.progress) progress = [&](const std::string&, double) { request.progress(0); };
  BakeResult baked = bake(scene, s, fp, progress);
  result.timings = baked.timings;
  StageClock clock(result.timings);
  gpu_.gl().make_current();
  if (!distance_program_) {
    distance_program_ = build_distance_program();
    shade_program_ = gpu::build_compute_program("shaders/single/shade.comp");
    splat_program_ = gpu::build_program("shaders/single/splat.vert", "shaders/single/splat.frag");
    splat_quad_program_ = gpu::build_program("shaders/single/splat.vert",
                                             "shaders/single/splat.frag", "#define QUAD_CUT 1\n");
    empty_vao_ = gpu::GlObject::create(gpu::GlKind::VertexArray);
  }
  if (!current_.uploaded) upload();
  const SingleBake& b = *current_.bake;

  const MeshBuffers& mesh = mesh_.get(scene);
  CameraMatrices cam = camera_matrices(scene);
  const Vec3& eye = scene.camera.position;
  // splat_scale: the splat evaluates every stride-th pixel of the image; the upsample below
  // fills in the rest.
  // coarse (exact_tr): the bake's coarse set, the first samples of its progressive order widened.
  const DrawnSamples drawn = drawn_samples(b, s.coarse && s.exact_tr);
  const double sigma_median = current_.sigma_median * drawn.sigma_scale;
  const int stride = splat_stride(s.splat_scale, sigma_median, scene);
  const double sigma_px = sigma_median * near_pixels_per_unit(scene);
  for (StagePlan& stage : result.plan.stages)
    if (stage.name == "splat" && s.coarse)
      stage.reason += drawn.coarse ? "; the coarse set: " + std::to_string(drawn.count()) +
                                         " of the " + std::to_string(b.count) +
                                         " pieces, sigma x " + exact_number(drawn.sigma_scale)
                                   : "; every sample (coarse needs exact_tr and 1024 samples)";
  const int lw = (scene.width + stride - 1) / stride, lh = (scene.height + stride - 1) / stride;
  for (StagePlan& stage : result.plan.stages)
    if (stage.name == "splat" && stride > 1)
      stage.reason += "; one pixel in " + std::to_string(stride) + " x " + std::to_string(stride) +
                      " (" + std::to_string(lw) + " x " + std::to_string(lh) +
                      (s.splat_scale > 0 ? ", splat_scale"
                                         : ": the median Gaussian spans " +
                                               std::to_string(int(sigma_px)) + " pixels") +
                      "), the rest interpolated along the view rays' chords";
  RenderTarget front(scene.width, scene.height), back(scene.width, scene.height);
  RenderTarget third(scene.width, scene.height), fourth(scene.width, scene.height);
  const GLuint dist = distance_program_.get();
  draw_distance(dist, mesh, front, cam.view, cam.projection, eye, Vec3{}, false, 0);
  if (s.clip_back) {
    draw_distance(dist, mesh, back, cam.view, cam.projection, eye, Vec3{}, false,
                  front.color_texture());
    draw_distance(dist, mesh, third, cam.view, cam.projection, eye, Vec3{}, false,
                  back.color_texture());
    draw_distance(dist, mesh, fourth, cam.view, cam.projection, eye, Vec3{}, false,
                  third.color_texture());
  }
  glFinish();
  clock.stop("depth_peel");

  const GLuint shade = shade_program_.get();
  if (s.exact_tr) {
    shade_exact(scene, drawn, s.tr_gradient, s.tr_hessian, s.tr_gradient_max, s.mesh_bound);
    current_.moved = true;
  } else if (current_.moved) {
    reset_moves();  // the SH path moves and stretches nothing
  }
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, positions_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, weights_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, sigma_s_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, sh_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, colors_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, sigmas_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, shifts_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, axes_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, planes_.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 9, cuts_.get());
  uniform1i(shade, "count", b.count);
  uniform1i(shade, "bands", b.params.sh_order);
  uniform1i(shade, "depth_mode", b.params.sh_depth ? 1 : 0);
  uniform3(shade, "eye", eye);
  glProgramUniform1f(shade, glGetUniformLocation(shade, "g"), float(scene.medium.g));
  set_light_uniforms(shade, scene.lights);
  if (!s.exact_tr) {
    glUseProgram(shade);
    glDispatchCompute(static_cast<GLuint>((b.count + 63) / 64), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  glFinish();
  clock.stop("shade");

  const bool quad_cut = s.exact_tr && s.tr_gradient && s.tr_hessian;  // else no cut to apply
  const GLuint splat = (quad_cut ? splat_quad_program_ : splat_program_).get();
  RenderTarget out(lw, lh);
  uniform_matrix(splat, "view_projection", cam.projection * cam.view);
  set_camera_uniforms(splat, scene);
  uniform1i(splat, "stride", stride);
  // The image's pixel (stride i, stride j) has its centre 1/2 - 1/(2 stride) of a target pixel
  // before the target's: move the quads forward by as much (2 / lw in clip space per pixel).
  const double shift = 0.5 - 0.5 / stride;
  glProgramUniform2f(splat, glGetUniformLocation(splat, "ndc_shift"), float(2 * shift / lw),
                     float(2 * shift / lh));
  uniform1i(splat, "front", 0);
  uniform1i(splat, "back", 1);
  uniform1i(splat, "third", 2);
  uniform1i(splat, "fourth", 3);
  uniform1i(splat, "clip_back", s.clip_back ? 1 : 0);
  // From inside the object the first surface is where the rays leave the medium.
  const bool inside = mesh_.eye_inside(scene);
  uniform1i(splat, "eye_inside", inside ? 1 : 0);
  // exact_tr with a peaked phase or the eye near the medium: each light's share without its phase,
  // which the fragment takes per view ray (phase_per_ray in single_pipeline.hpp).
  const bool per_ray = s.exact_tr && phase_per_ray(scene, current_.sigma_median);
  uniform1i(splat, "per_ray_phase", per_ray ? 1 : 0);
  note_frame(result.plan, scene, s, inside, per_ray);
  glProgramUniform1f(splat, glGetUniformLocation(splat, "g"), float(scene.medium.g));
  set_light_uniforms(splat, scene.lights);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 10, s.exact_tr ? light_factors_.get() : 0);
  glBindTextureUnit(0, front.color_texture());
  glBindTextureUnit(1, back.color_texture());
  glBindTextureUnit(2, third.color_texture());
  glBindTextureUnit(3, fourth.color_texture());
  out.bind_and_clear(Vec3{});  // the term alone, as the reference renders it
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_DEPTH_CLAMP);  // quads of balls near the eye may cross the near plane
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE);
  glUseProgram(splat);
  glBindVertexArray(empty_vao_.get());
  for (const auto& [first, count] : drawn.ranges) {
    uniform1i(splat, "first", first);
    glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, count);
  }
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_CLAMP);
  glBindTextureUnit(0, 0);
  glBindTextureUnit(1, 0);
  glBindTextureUnit(2, 0);
  glBindTextureUnit(3, 0);
  for (GLuint i = 0; i <= 10; ++i) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, 0);
  gpu::check_gl("single splat");
  glFinish();
  clock.stop("splat");

  if (stride > 1) {
    result.image = upsample(out, {&front, &back, &third, &fourth}, stride, s.clip_back, inside,
                            scene, per_ray);
    clock.stop("upsample");
  } else {
    result.image = out.read_color();
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  clock.stop("readback");
  return result;
}

}  // namespace scatter
