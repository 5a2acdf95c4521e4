// Spectral delta tracking, exact and ratio-tracked transmittance in the voxel medium with
// per-brick majorants, all three colour channels at once; after rng.cl and dda.cl. Part of the
// kernels' shared library (pipelines/common/cl_library.hpp).
//
// One path carries the three channels with per-channel weights (Kutz et al. 2017, "Spectral and
// decomposition tracking"; as pbrt-v4's SampledSpectrum majorant tracking with one majorant for
// all wavelengths). The majorant m of a brick bounds every channel's sigma_t, so the tentative
// collisions are common to the channels; at each one the path takes the real collision with
// probability P = sum_c w_c sigma_t,c / (m sum_c w_c) (the history-aware average) and multiplies
// each weight by sigma_s,c / (m P), or goes on as a null collision with weights times
// sigma_n,c / (m (1 - P)), sigma_n = m - sigma_t. Each channel's expectation is delta tracking's
// with absorption as a weight: unbiased for every channel, and for a grey medium exactly the
// one-channel tracker (P = sigma_t / m, weights times the albedo at real collisions only).

// ---- Tracking in the voxel medium with per-brick majorants -----------------------------------

// The voxel medium as the trackers read it: the grid, the voxels' coefficients (RGB interleaved),
// per brick the majorant and the index of a voxel whose coefficients the whole brick shares (< 0
// when they differ or no segment reaches it: pipelines/reference/inside_grid.hpp,
// uniform_bricks), and the index of a voxel whose coefficients every segment the trackers are
// given sees (homogeneous_voxel: a constant density inside the mesh that bounds the medium), or
// -1. Then tracking and optical depth take no walk.
typedef struct {
  Grid g;
  __global const float* sigma_s;
  __global const float* sigma_t;
  __global const float* majorant;
  __global const int* uniform;
  int homogeneous;
} Medium;

float3 voxel_sigma3(const Grid* g, __global const float* sigma, int3 c) {
  if (c.x < 0 || c.y < 0 || c.z < 0 || c.x >= g->nx || c.y >= g->ny || c.z >= g->nz)
    return (float3)(0.0f);
  __global const float* p = sigma + 3 * voxel_index(g, c.x, c.y, c.z);
  return (float3)(p[0], p[1], p[2]);
}

float max3(float3 v) { return fmax(v.x, fmax(v.y, v.z)); }

int brick_index(const Grid* g, int3 c) { return (c.z * g->by + c.y) * g->bx + c.x; }

// Starts a walk over the bricks crossed by o + t d, t < tmax; false if the ray misses the grid.
bool brick_walk(const Grid* g, float3 o, float3 d, float tmax, Dda* s) {
  float g0, g1;
  if (!grid_interval(g, o, d, &g0, &g1)) return false;
  g1 = fmin(g1, tmax);
  if (g1 <= g0) return false;
  dda_init(s, o, d, g->origin, g->voxel * g->brick, (int3)(g->bx, g->by, g->bz), g0, g1);
  return true;
}

// A brick whose majorant would draw more than this many tentative collisions per voxel the ray
// crosses there is walked voxel by voxel instead, each voxel's own largest sigma being its
// majorant: a brick that holds a dense blocker (sigma up to 1e6) beside a thin medium would
// otherwise take majorant / sigma null collisions per real one (seconds per pixel).
#define VOXEL_WALK_RATIO 1.0f

// Whether segment [a, b] of a brick with majorant m is walked voxel by voxel.
bool walk_voxels(const Grid* g, float m, float a, float b) {
  return m * (b - a) > VOXEL_WALK_RATIO * g->brick;
}

// The next tentative collision after t at rate m, or b when it falls past b. A step below t's
// float32 resolution (a dense brick far from the origin) ends the segment rather than looping.
float next_tentative(float t, float m, float b, Rng* r) {
  float tn = t - log(1.0f - rng_uniform(r)) / m;
  return tn > t && tn < b ? tn : b;
}

// A tentative collision at majorant m where the medium has sigma_s ss and sigma_t st: true (and
// the weights of a real collision) or false (those of a null one), as in the header.
bool spectral_collide(float m, float3 ss, float3 st, float3* w, Rng* r) {
  float3 sn = fmax(m - st, (float3)(0.0f));
  float real = dot(*w, st), null = dot(*w, sn);
  if (real <= 0.0f) return false;  // no channel can collide here: a null collision, weights kept
  float p = real / (real + null);
  if (rng_uniform(r) < p) {
    *w *= ss / (m * p);
    return true;
  }
  *w *= sn / (m * (1.0f - p));
  return false;
}

// An exponential sample of optical depth (mean 1) from a uniform in [0, 1).
float exp_depth(float u) { return -log(1.0f - u); }

// Delta tracking's next tentative collision after *t at rate m, before b: it falls where the
// majorant's optical depth since the last one reaches *tau, an exponential sample. Past b the depth
// left stays in *tau for the next stretch: a flight is memoryless, so carrying it on is delta
// tracking too, and the flight's first sample (stratified, path.cl) then sets where its first
// tentative collision falls across any number of bricks. A step below t's float32 resolution (a
// dense brick far from the origin) ends the stretch with a fresh sample rather than looping.
bool tentative_step(float* t, float m, float b, float* tau, Rng* r) {
  float tn = *t + *tau / m;
  if (tn >= b) {
    *tau = fmax(*tau - m * (b - *t), 0.0f);
    return false;
  }
  if (tn > *t || *tau <= 0.0f) {  // (a depth used up at the stretch's start: a collision there)
    *t = tn;
    return true;
  }
  *tau = exp_depth(rng_uniform(r));
  return false;
}

// Tentative collisions at rate m over [a, b] in a stretch of constant coefficients ss, st.
bool track_constant(float m, float3 ss, float3 st, float a, float b, float3* w, Rng* r,
                    float* tau, float* t_hit) {
  for (float t = a; tentative_step(&t, m, b, tau, r); *tau = exp_depth(rng_uniform(r)))
    if (spectral_collide(m, ss, st, w, r)) {
      *t_hit = t;
      return true;
    }
  return false;
}

// Spectral delta tracking: the first real collision along o + t d, t < tmax; *w takes the
// collisions' weights (header), *tau is the optical depth to the next tentative collision
// (tentative_step: the caller draws it where a flight starts, and a flight that reaches tmax
// leaves the rest in it to go on with). Empty bricks are stepped over; a uniform brick draws its
// tentative collisions at its own largest sigma_t; within other bricks they are drawn at the
// brick's majorant or (walk_voxels) at each voxel's largest sigma_t.
bool delta_track(const Medium* md, float3 o, float3 d, float tmax, float3* w, Rng* r,
                 float* tau, float* t_hit) {
  if (md->homogeneous >= 0) {
    float3 st = vload3(md->homogeneous, md->sigma_t);
    float m = max3(st);
    return m > 0.0f &&
           track_constant(m, vload3(md->homogeneous, md->sigma_s), st, 0.0f, tmax, w, r, tau,
                          t_hit);
  }
  const Grid* g = &md->g;
  Dda s;
  if (!brick_walk(g, o, d, tmax, &s)) return false;
  float a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    int bi = brick_index(g, c);
    float m = md->majorant[bi];
    if (m <= 0.0f) continue;
    int u = md->uniform[bi];
    if (u >= 0) {
      float3 st = vload3(u, md->sigma_t);
      float mu = max3(st);
      if (mu > 0.0f && track_constant(mu, vload3(u, md->sigma_s), st, a, b, w, r, tau, t_hit))
        return true;
      continue;
    }
    if (walk_voxels(g, m, a, b)) {
      Dda v;
      dda_init(&v, o, d, g->origin, g->voxel, (int3)(g->nx, g->ny, g->nz), a, b);
      float va, vb;
      int3 vc;
      while (dda_next(&v, &va, &vb, &vc)) {
        float3 st = voxel_sigma3(g, md->sigma_t, vc);
        float mv = max3(st);
        if (mv <= 0.0f) continue;
        if (track_constant(mv, voxel_sigma3(g, md->sigma_s, vc), st, va, vb, w, r, tau, t_hit))
          return true;
      }
      continue;
    }
    for (float t = a; tentative_step(&t, m, b, tau, r); *tau = exp_depth(rng_uniform(r))) {
      int3 vc = voxel_of(g, o + d * t);
      if (spectral_collide(m, voxel_sigma3(g, md->sigma_s, vc), voxel_sigma3(g, md->sigma_t, vc),
                           w, r)) {
        *t_hit = t;
        return true;
      }
    }
  }
  return false;
}

// The three channels' optical depth along o + t d, t in [a, b] inside brick c (not empty).
float3 brick_depth(const Medium* md, int bi, float3 o, float3 d, float a, float b) {
  const Grid* g = &md->g;
  int u = md->uniform[bi];
  if (u >= 0) return vload3(u, md->sigma_t) * (b - a);
  Dda v;
  dda_init(&v, o, d, g->origin, g->voxel, (int3)(g->nx, g->ny, g->nz), a, b);
  float va, vb;
  int3 vc;
  float3 tau = (float3)(0.0f);
  while (dda_next(&v, &va, &vb, &vc)) tau += voxel_sigma3(g, md->sigma_t, vc) * (vb - va);
  return tau;
}

// The exact transmittance of the three channels along o + t d, t in [0, tmax]: the optical depth
// summed voxel by voxel (each voxel is constant; a uniform brick at once), walking only the
// bricks that hold any medium. No randomness: a shadow ray's transmittance without the variance
// of ratio tracking, whose estimate where the majorant is tight (a homogeneous medium) is 0 or 1.
float3 exact_transmittance(const Medium* md, float3 o, float3 d, float tmax) {
  if (md->homogeneous >= 0) return exp(-vload3(md->homogeneous, md->sigma_t) * tmax);
  const Grid* g = &md->g;
  Dda s;
  if (!brick_walk(g, o, d, tmax, &s)) return (float3)(1.0f);
  float3 tau = (float3)(0.0f);
  float a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    int bi = brick_index(g, c);
    if (md->majorant[bi] <= 0.0f) continue;
    tau += brick_depth(md, bi, o, d, a, b);
    if (max3(-tau) < -80.0f) return (float3)(0.0f);  // below float32's range in every channel
  }
  return exp(-tau);
}

// Ratio tracking of the three channels at once: an unbiased estimate of each channel's
// transmittance along o + t d, t in [0, tmax], with Russian roulette once the largest is small so
// dense media end early. A brick walked voxel by voxel (walk_voxels) or uniform contributes its
// exact transmittance.
float3 ratio_track(const Medium* md, float3 o, float3 d, float tmax, Rng* r) {
  const Grid* g = &md->g;
  Dda s;
  float3 tr = (float3)(1.0f);
  if (!brick_walk(g, o, d, tmax, &s)) return tr;
  float a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    int bi = brick_index(g, c);
    float m = md->majorant[bi];
    if (m <= 0.0f) continue;
    if (md->uniform[bi] >= 0 || walk_voxels(g, m, a, b)) {
      tr *= exp(-brick_depth(md, bi, o, d, a, b));
    } else {
      for (float t = next_tentative(a, m, b, r); t < b; t = next_tentative(t, m, b, r))
        tr *= fmax(1.0f - voxel_sigma3(g, md->sigma_t, voxel_of(g, o + d * t)) / m,
                   (float3)(0.0f));
    }
    float top = max3(tr);
    if (top < 0.01f) {
      if (top <= 0.0f || rng_uniform(r) >= 0.5f) return (float3)(0.0f);
      tr *= 2.0f;
    }
  }
  return tr;
}
