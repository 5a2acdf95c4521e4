#include "pipelines/lbl/lbl_frame.hpp"

#include <algorithm>
#include <cmath>

#include "bake/cache.hpp"
#include "core/errors.hpp"
#include "pipelines/asset_key.hpp"
#include "pipelines/cost_support.hpp"
#include "pipelines/lbl/lbl_limits.hpp"

namespace scatter::lbl {
namespace {

// A scattered photon's chance to scatter again somewhere in the volume, at most.
double second_scatter_bound(double max_sigma_s, double longest_side) {
  return -std::expm1(-max_sigma_s * longest_side);
}

}  // namespace

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

bool uses_flux_phase(const Scene& scene, const LblSettings& s) {
  return s.flux_phase && scene.medium.g != 0 && s.directions == 6;
}

bool uses_tms(const Scene& scene, const LblSettings& s) {
  // Only a forward peak is a truncation: with g < 0 sigma_t' exceeds sigma_t and the single
  // term's "gain" through it would be a loss (a negative multiple term).
  return s.tms && !s.scaled_view && scene.medium.g > 0;
}

bool uses_second(const LblSettings& s) {
  return s.second && s.directions == 6 && s.interleave == 0;
}

int light_lobes(const Scene& scene, const LblSettings& s) {
  const int lights = static_cast<int>(scene.lights.size());
  if (scene.medium.g == 0 || lights < 2 || s.interleave > 0) return 1;
  const int margin = 1 + static_cast<int>(std::ceil(3 * s.smooth));
  const double nodes = cost::grid_shape(scene, margin, s.blocked ? s.block : 1).count();
  const double fit = std::floor(kMaxLobeBytes / (36.0 * std::max(nodes, 1.0)));
  const int lobes = static_cast<int>(std::min({double(lights), double(s.lobes), fit}));
  return lobes >= 2 ? lobes : 1;
}

std::vector<std::vector<int>> light_groups(const Scene& scene, int lobes) {
  const int n = static_cast<int>(scene.lights.size());
  lobes = std::clamp(lobes, 1, std::max(n, 1));
  std::vector<std::vector<int>> groups(static_cast<size_t>(lobes));
  if (lobes == n) {
    for (int i = 0; i < n; ++i) groups[size_t(i)] = {i};
    return groups;
  }
  // Each light's direction from the object's centre.
  const Vec3 centre = scene.mesh->bounds().center();
  std::vector<Vec3> dir(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const Light& l = scene.lights[size_t(i)];
    Vec3 d = l.type == Light::Type::Directional ? -l.direction : l.position - centre;
    dir[size_t(i)] = length(d) > 0 ? d / length(d) : Vec3{0, 0, 1};
  }
  // Centres: the first light, then each time the light least like every centre so far.
  std::vector<Vec3> c = {dir[0]};
  while (int(c.size()) < lobes) {
    int far = 0;
    double worst = 2;
    for (int i = 0; i < n; ++i) {
      double best = -2;
      for (const Vec3& m : c) best = std::max(best, dot(dir[size_t(i)], m));
      if (best < worst) worst = best, far = i;
    }
    c.push_back(dir[size_t(far)]);
  }
  std::vector<int> of(static_cast<size_t>(n), -1);
  for (int iteration = 0; iteration < 16; ++iteration) {
    bool moved = false;
    for (int i = 0; i < n; ++i) {
      int best = 0;
      for (int k = 1; k < lobes; ++k)
        if (dot(dir[size_t(i)], c[size_t(k)]) > dot(dir[size_t(i)], c[size_t(best)])) best = k;
      moved |= of[size_t(i)] != best;
      of[size_t(i)] = best;
    }
    if (!moved) break;
    for (int k = 0; k < lobes; ++k) {
      Vec3 sum{0, 0, 0};
      for (int i = 0; i < n; ++i)
        if (of[size_t(i)] == k) sum = sum + dir[size_t(i)];
      if (length(sum) > 0) c[size_t(k)] = sum / length(sum);
    }
  }
  // A centre no light chose (lights in fewer distinct directions than lobes): its group takes a
  // light from the largest group, so that every deposit holds one.
  for (int i = 0; i < n; ++i) groups[size_t(of[size_t(i)])].push_back(i);
  for (auto& g : groups) {
    if (!g.empty()) continue;
    auto largest = std::max_element(groups.begin(), groups.end(), [](const auto& a, const auto& b) {
      return a.size() < b.size();
    });
    g.push_back(largest->back());
    largest->pop_back();
  }
  std::sort(groups.begin(), groups.end());
  return groups;
}

Decision decide(const State* state, const Scene& scene, const RenderRequest& request,
                const LblSettings& s) {
  Decision d;
  d.material = !state || state->material != material_key(scene, s);
  d.march = d.material || state->lights != light_key(scene, s);
  d.single = request.terms != Terms::Multiple;
  d.multiple = request.terms != Terms::Single;
  d.bend = scene.medium.ior != 1.0;
  if (!d.material) {
    const Volume& v = state->volume;
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
  d.gather = d.diffuse && uses_second(s) &&
             (d.march || !state->second_current || state->second_gathers != s.gathers);
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
          (uses_second(s) && !d.gather
               ? "; from the light's second scattering, kept (the deposit is unchanged)"
           : uses_second(s)
               ? "; from the light's second scattering, gathered over " +
                     std::to_string(kSecondDirections) + " directions through the scaled medium" +
                     (s.escape_stride > 1 ? " at one voxel in " + std::to_string(s.escape_stride) +
                                                " per axis as the escape correction"
                                          : std::string(" at every voxel")) +
                     (s.gathers > 1
                          ? ", the orders 3 to " + std::to_string(s.gathers + 1) +
                                " each gathered from the last at half resolution (the lattice "
                                "carries the later events)"
                          : std::string(" (the lattice carries the third and later events)"))
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
  const int lobes = light_lobes(scene, s);
  const size_t lights = scene.lights.size();
  std::string lobe_text;
  if (lobes > 1 && size_t(lobes) == lights)
    lobe_text =
        "; each light's deposit and direction kept apart (the single term by each "
        "light's phase lobe)";
  else if (lobes > 1)
    lobe_text = "; the lights grouped by direction into " + std::to_string(lobes) + " deposits (" +
                (lights > size_t(s.lobes) ? "more lights than lobes " + std::to_string(s.lobes)
                                          : std::string("the lights' deposits would take over "
                                                        "512 MiB")) +
                "), each group's kept apart (the single term by each group's phase lobe about "
                "its mean direction)";
  else if (scene.medium.g != 0 && lights > 1)
    lobe_text =
        "; the lights' deposits summed, the single term by one phase lobe about their "
        "mean direction (" +
        std::string(s.interleave > 0 ? "interleaved march"
                    : s.lobes < 2    ? "lobes " + std::to_string(s.lobes)
                                     : "two lights' deposits would take over 512 MiB") +
        ")";
  p.stages.push_back({"march", d.march,
                      d.march ? std::to_string(lights) + " lights, " + short_number(s.rays) +
                                    " rays per voxel width, " + path +
                                    "; deposits added by CAS atomics" + lobe_text
                              : "lights and material unchanged: deposit kept"});
  p.stages.push_back(diffuse_stage(d, s));
  if (s.measure)
    p.stages.push_back({"bandwidth", d.diffuse,
                        d.diffuse ? "16 more lattice steps and 16 copies of its state, timed"
                                  : "nothing diffused in this frame"});
  std::string gathers =
      d.single && d.multiple ? "deposit + lattice" : (d.single ? "the deposit" : "the lattice");
  std::string phase =
      scene.medium.g != 0
          ? "; HG phase (g " + short_number(scene.medium.g) +
                ") about the light's direction for the single term and the "
                "forward-scattered light" +
                (uses_second(s) && s.second_phase
                     ? std::string(", about the gather's mean direction for the "
                                   "second scattering's light")
                     : std::string()) +
                ", the lattice's (delta-Eddington scaled) light " +
                (uses_tms(scene, s) ? std::string("emitted by sigma_s (1 - g), ") : std::string()) +
                (uses_flux_phase(scene, s)
                     ? std::string("scattered by the phase's first moment about its flux")
                     : std::string("isotropically")) +
                (uses_tms(scene, s) ? std::string("; the whole multiple term seen through the "
                                                  "scaled medium, with what the single term's "
                                                  "light gains there (TMS)")
                 : s.scaled_view    ? std::string(" and seen through the scaled medium")
                                    : std::string())
          : "";
  // Where the multiple term is least accurate, and why (docs/BENCHMARKS.md, lbl: with the TMS
  // reading, spheres at g 0.7 4-14 % on all terms, the thick ones the most, at g 0.9 8 %, a
  // slab-like box under a grazing sun at g 0.75 12-15 %; at g -0.3 8 %, at g -0.7 35 %).
  const std::string caveat =
      !d.multiple ? ""
      : scene.medium.g >= 0.6
          ? "; at g " + short_number(scene.medium.g) +
                " the multiple term is lbl's least accurate (a delta-Eddington lattice behind "
                "the scaled problem's exact orders: all terms measured 4-14 % off at g 0.7-0.9, "
                "the most in optically thick media and under grazing light)"
      : scene.medium.g < kMultipleMeasuredMinG
          ? "; at g " + short_number(scene.medium.g) +
                " the multiple term is lbl's least accurate (back-scattering, no forward peak "
                "for the delta-Eddington lattice to keep: all terms measured 35 % off at g "
                "-0.7, 8 % at g -0.3)"
          : "";
  p.stages.push_back(
      {"view", true,
       std::string(d.bend ? "eye rays refracted by grad n" : "straight eye rays (DDA)") +
           ", gathering " + gathers + phase + caveat});
  p.stages.push_back({"readback", true, "linear RGB to the host"});
  return p;
}

}  // namespace scatter::lbl
