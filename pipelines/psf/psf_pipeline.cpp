#include "pipelines/psf/psf_pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <sstream>
#include <string>

#include "pipelines/asset_key.hpp"
#include "pipelines/common/stage_clock.hpp"
#include "scene/voxelizer.hpp"

namespace scatter {
namespace {

std::string medium_fingerprint(const Scene& scene) {
  BakeKey k = asset_key(scene);
  k.add("g", scene.medium.g);
  return k.hex();
}

}  // namespace

void PsfPipeline::prepare(const Scene& scene) {
  std::string fp = medium_fingerprint(scene);
  if (medium_.cl && medium_.fingerprint == fp) return;
  VoxelGrid grid = voxelize(scene, {.resolution = scene.voxels});
  gpu::ClContext& cl = gpu_.cl();
  medium_.lights.clear();
  medium_.cl = std::make_unique<ClMedium>(upload_medium(cl, grid));
  medium_.occupancy = upload(cl, grid.occupancy);
  medium_.fingerprint = fp;
  medium_.density = scene.medium.density;
  float max_s = 0;
  for (float v : grid.sigma_s) max_s = std::max(max_s, v);
  // The orders' mean free path: b over the voxels holding medium (weighted by their share of
  // it), and c from the medium's own albedo (a blocker's absorption is not the medium's).
  std::array<double, 3> sum_s{};
  double occupied = 0;
  for (size_t v = 0; v < grid.count(); ++v) {
    if (grid.sigma_s[3 * v] + grid.sigma_s[3 * v + 1] + grid.sigma_s[3 * v + 2] <= 0) continue;
    occupied += grid.occupancy[v];
    for (int c = 0; c < 3; ++c) sum_s[c] += grid.sigma_s[3 * v + c];
  }
  const Vec3 ms = scene.medium.sigma_s, ma = scene.medium.sigma_a;
  const double mss[3] = {ms.x, ms.y, ms.z}, mas[3] = {ma.x, ma.y, ma.z};
  for (int c = 0; c < 3; ++c)
    medium_.mean_sigma_t[c] =
        occupied > 0 && mss[c] > 0 ? sum_s[c] / occupied * (1 + mas[c] / mss[c]) : 0.0;
  medium_.orders.clear();
  thickness_ = double(max_s) * grid.voxel * std::max({grid.nx, grid.ny, grid.nz});
  medium_.pms = psf::pms_table(scene.medium.g);
  medium_.pms_buf = upload(cl, medium_.pms.inv_norm);
}

std::vector<std::string> PsfPipeline::light_keys(const Scene& scene) const {
  std::vector<float> packed = pack_lights(scene.lights);
  std::vector<std::string> keys;
  for (size_t i = 0; i < scene.lights.size(); ++i)
    keys.emplace_back(reinterpret_cast<const char*>(packed.data() + 16 * i), 16 * sizeof(float));
  return keys;
}

void PsfPipeline::check_memory(const Scene& scene) {
  // Per light: three float4 volumes and the pyramid (1 + 1/8 + ... < 8/7 of a volume); the medium:
  // sigma_s and sigma_t (RGB floats) and the occupancy (a float). The grid has at most
  // (voxels + 2)^3 voxels.
  const double n = std::pow(double(scene.voxels) + 2, 3);
  const double per_light = n * 16 * (3 + 8.0 / 7), pyramid = n * 16 * 8.0 / 7;
  const double need = per_light * std::max<size_t>(scene.lights.size(), 1) + n * 28;
  const gpu::ClDeviceInfo& info = gpu_.cl().info();
  const double have = 0.75 * double(info.global_memory);
  auto mib = [](double b) {
    return std::to_string(static_cast<long long>(b / (1 << 20))) + " MiB";
  };
  if ((info.global_memory > 0 && need > have) ||
      (info.max_alloc > 0 && pyramid > double(info.max_alloc)))
    throw ValidationError(
        "scene.voxels",
        "the psf pipeline needs up to " + mib(need) + " of device memory for " +
            std::to_string(scene.voxels) + " voxels and " + std::to_string(scene.lights.size()) +
            " lights (a light pyramid up to " + mib(pyramid) + "); the device offers " + mib(have) +
            " (largest buffer " + mib(double(info.max_alloc)) + "): use fewer voxels or lights");
}

psf::OrderParams PsfPipeline::order_params(const Scene& scene, const PsfSettings& s) const {
  return {.g = scene.medium.g,
          .mean_sigma_t = medium_.mean_sigma_t,
          .level = s.level,
          .flights = s.flights,
          .drift = s.drift >= 0 ? s.drift : psf::calibrated_drift(scene.medium.g),
          .tail = s.tail,
          .conserve = s.conserve};
}

bool PsfPipeline::orders_held(const std::string& key, const psf::OrderParams& op) const {
  auto v = medium_.lights.find(key);
  auto it = medium_.orders.find(key);
  if (!medium_.cl || v == medium_.lights.end() || it == medium_.orders.end()) return false;
  const int level =
      psf::orders_level(op, medium_.cl->voxel, static_cast<int>(v->second.pyramid.layout.size()));
  return it->second.level == level && it->second.flights == op.flights &&
         it->second.tail == op.tail && it->second.drift == op.drift &&
         it->second.conserve == op.conserve;
}

Plan PsfPipeline::make_plan(const Scene& scene, const RenderRequest& request, const PsfSettings& s,
                            bool held, double thickness, const std::string& thickness_note) const {
  Plan p{name(), request.terms, {}};
  p.stages.push_back({"voxelize", !held,
                      held ? "the medium is the one already held (camera or lights changed)"
                           : std::to_string(scene.voxels) + " voxels on the long side"});
  const bool multiple = request.terms != Terms::Single;
  const bool thin = thickness < s.thin;
  int changed = 0, new_orders = 0;  // lights whose volume, or whose orders, are to be built
  for (const auto& key : light_keys(scene)) {
    const bool kept = held && !s.rebuild && medium_.lights.count(key);
    changed += kept ? 0 : 1;
    new_orders += kept && orders_held(key, order_params(scene, s)) ? 0 : 1;
  }
  const int n = static_cast<int>(scene.lights.size());
  std::string lights = std::to_string(changed) + " of " + std::to_string(n) + " lights";
  p.stages.push_back({"light_volume", changed > 0,
                      changed ? lights + " new or changed: transmittance, scattering events and "
                                         "length towards the light per voxel"
                              : "every light's volume is held (camera-only change)"});
  const bool need_pyramid = multiple && !thin;
  p.stages.push_back({"pyramid", need_pyramid && changed > 0,
                      !need_pyramid ? "the multiple term is not rendered"
                      : changed     ? lights + ": Gaussian pyramid of the scattered light"
                                    : "every light's pyramid is reused (camera-only change)"});
  const bool orders = need_pyramid && s.model == 1;
  const std::string order_lights =
      std::to_string(new_orders) + " of " + std::to_string(n) + " lights";
  p.stages.push_back(
      {"orders", orders && new_orders > 0,
       !need_pyramid ? "the multiple term is not rendered"
       : !orders     ? "model 0 (the paper's): the march reads the pyramid at one path length"
       : new_orders  ? order_lights +
                          ": the scattering orders on a coarse pyramid level, each spread and "
                          "drifted by its flight (model 1, orders" +
                          (s.conserve ? std::string(", each flight's collisions conserved)")
                                      : std::string(", b capped at the albedo x mean c)"))
                    : "every light's orders are reused (camera-only change)"});
  p.stages.push_back({"march_single", request.terms != Terms::Multiple,
                      request.terms == Terms::Multiple ? "single term not requested"
                                                       : "sub-steps of " + short_number(s.step) +
                                                             " voxels, light volume trilinear"});
  std::string ms_reason;
  if (!multiple)
    ms_reason = "multiple term not requested";
  else if (thin)
    ms_reason = "optically thin (scattering thickness " + short_number(thickness) + thickness_note +
                " < " + short_number(s.thin) + "): multiple scattering is negligible";
  else if (s.model == 1)
    ms_reason = "model 1 (orders): the orders' bands with their phases HG(g^(m+1)), every sub-step";
  else
    ms_reason = "model 0 (the paper's): pyramid lookups at the equation-18 width, every " +
                short_number(s.spacing) + " projected blur width; attenuation " +
                (s.atten == 0   ? "over the whole path (paper)"
                 : s.atten == 1 ? "of the view segment"
                                : "by absorption only");
  p.stages.push_back({"march_multiple", multiple && !thin, ms_reason});
  if (scene.medium.ior != 1.0)
    p.stages.push_back(
        {"boundary", false,
         "refraction and Fresnel are neglected (ior " + short_number(scene.medium.ior) + ")"});
  p.stages.push_back({"readback", true, "linear RGB to the host"});
  return p;
}

// Pure: no GPU, no voxelizing. Before the medium is voxelized its scattering thickness is
// estimated at density 1 over the mesh's extent; render() decides with the voxels' own.
Plan PsfPipeline::plan(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  PsfSettings s = PsfSettings::read(request.settings);
  const bool held = medium_.cl && medium_.fingerprint == medium_fingerprint(scene);
  if (held) return make_plan(scene, request, s, true, thickness_, "");
  Aabb box = scene.mesh->bounds();
  Vec3 size = box.size();
  const double longest = std::max({size.x, size.y, size.z});
  const double voxel = longest / scene.voxels;
  const double ms =
      std::max({scene.medium.sigma_s.x, scene.medium.sigma_s.y, scene.medium.sigma_s.z});
  return make_plan(scene, request, s, false, ms * voxel * (scene.voxels + 2),
                   " estimated at density 1");
}

RenderResult PsfPipeline::render(const Scene& scene, const RenderRequest& request) {
  RenderResult result;
  require_terms(*this, request.terms);
  PsfSettings s = PsfSettings::read(request.settings);
  StageClock clock(result.timings);
  if (s.rebuild) medium_.lights.clear();
  check_memory(scene);
  const bool held = medium_.cl && medium_.fingerprint == medium_fingerprint(scene);
  prepare(scene);  // voxelizes and uploads when the medium changed
  result.plan = make_plan(scene, request, s, held, thickness_, "");
  clock.stop("voxelize");
  gpu::ClContext& cl = gpu_.cl();
  auto& queue = cl.queue();
  const ClMedium& m = *medium_.cl;
  cl::Buffer lights = upload(cl, pack_lights(scene.lights));
  cl::Buffer camera = upload(cl, pack_camera(scene.camera, scene.width, scene.height));

  // Light volumes: build the new ones, drop those of lights no longer in the scene.
  std::vector<std::string> keys = light_keys(scene);
  std::map<std::string, psf::LightVolume> kept;
  double light_ms = 0, pyramid_ms = 0;
  for (size_t i = 0; i < keys.size(); ++i) {
    auto it = medium_.lights.find(keys[i]);
    if (it != medium_.lights.end()) {
      kept.emplace(keys[i], std::move(it->second));
      medium_.lights.erase(it);
      continue;
    }
    if (kept.count(keys[i])) continue;
    psf::LightVolume v = psf::build_light_volume(cl, m, lights, static_cast<int>(i));
    medium_.orders.erase(keys[i]);  // built from the volume just replaced
    light_ms += v.light_ms;
    pyramid_ms += v.pyramid_ms;
    ++light_builds_;
    kept.emplace(keys[i], std::move(v));
  }
  medium_.lights = std::move(kept);
  for (auto it = medium_.orders.begin(); it != medium_.orders.end();)
    it = medium_.lights.count(it->first) ? std::next(it) : medium_.orders.erase(it);
  result.timings.push_back({"light_volume", light_ms});
  result.timings.push_back({"pyramid", pyramid_ms});
  const bool thin_medium = thickness_ < s.thin;
  double orders_ms = 0;
  if (s.model == 1 && request.terms != Terms::Single && !thin_medium) {
    const psf::OrderParams op = order_params(scene, s);
    for (size_t i = 0; i < keys.size(); ++i) {
      const psf::LightVolume& v = medium_.lights.at(keys[i]);
      if (orders_held(keys[i], op)) continue;
      psf::Orders o =
          psf::build_orders(cl, m, medium_.occupancy, v.pyramid, lights, static_cast<int>(i), op);
      orders_ms += o.ms;
      medium_.orders.insert_or_assign(keys[i], std::move(o));
    }
  }
  result.timings.push_back({"orders", orders_ms});
  clock.restart();

  const int w = scene.width, h = scene.height;
  const size_t floats = size_t(w) * h * 3;
  std::vector<float> zeros(floats, 0.f);
  cl::Buffer out(cl.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, floats * sizeof(float),
                 zeros.data());
  const bool thin = thin_medium;
  const int terms = (request.terms != Terms::Multiple ? 1 : 0) |
                    (request.terms != Terms::Single && !thin ? 2 : 0);
  const float g = static_cast<float>(scene.medium.g);
  const float theta2 = static_cast<float>(psf::mean_square_angle(scene.medium.g));
  const float alpha = static_cast<float>(psf::curvature_alpha(scene.medium.g));
  cl::Kernel k(psf::program(cl), "psf_march");
  // Model 1's flux term: 3 g D / (4 pi) per channel, D = 1 / (3 c) (one flight's) or, flux 2,
  // 1 / (3 c (1 - g)) (diffusion's, with the reduced coefficient).
  cl_float4 flux{{0, 0, 0, 0}};
  for (int c = 0; c < 3 && s.flux > 0; ++c) {
    const double st = medium_.mean_sigma_t[c], gg = scene.medium.g;
    if (st <= 0) continue;
    const double D = 1 / (3 * st * (s.flux == 2 ? 1 - gg : 1.0));
    flux.s[c] = static_cast<float>(3 * gg * D / (4 * std::numbers::pi));
  }
  for (size_t i = 0; i < keys.size() && terms; ++i) {
    const psf::LightVolume& v = medium_.lights.at(keys[i]);
    const bool orders = s.model == 1 && (terms & 2);
    const psf::Orders* o = orders ? &medium_.orders.at(keys[i]) : nullptr;
    gpu::set_args(
        k, m.origin, m.voxel, m.nx, m.ny, m.nz, m.sigma_s, m.sigma_t, lights, static_cast<int>(i),
        g, camera, w, h, static_cast<float>(s.step), terms, v.l0, v.path, v.tau, v.pyramid.data,
        v.pyramid.levels, v.pyramid.widths, static_cast<int>(v.pyramid.layout.size()),
        medium_.pms_buf, static_cast<int>(medium_.pms.inv_norm.size()),
        static_cast<float>(medium_.pms.log_min), static_cast<float>(medium_.pms.log_max), theta2,
        alpha, static_cast<float>(s.shift), s.atten, static_cast<float>(s.spacing), orders ? 1 : 0,
        o ? o->bands : v.pyramid.data, o ? o->nx : 1, o ? o->ny : 1, o ? o->nz : 1,
        o ? o->cell : 1.f, flux, o && o->conserve ? o->cell : 0.f, out);
    // In bands of rows where a progress can stop it: a live view's pose waits for a band, not for
    // a whole march (seconds at 512^2).
    const size_t band = request.progress ? std::max<size_t>(8, (size_t(h) + 15) / 16) : size_t(h);
    for (size_t y = 0; y < size_t(h); y += band) {
      const size_t rows = std::min(band, size_t(h) - y);
      queue.enqueueNDRangeKernel(k, cl::NDRange(0, y), cl::NDRange(w, rows));
      if (request.progress) {
        queue.finish();
        request.progress((double(i) + double(y + rows) / h) / keys.size());
      }
    }
  }
  queue.finish();
  clock.stop("march");
  result.image = Image(w, h);
  queue.enqueueReadBuffer(out, CL_TRUE, 0, floats * sizeof(float), result.image.rgb.data());
  clock.stop("readback");
  return result;
}

}  // namespace scatter
