// Delta and ratio tracking in the voxel medium with per-brick majorants; after rng.cl and dda.cl.
// Part of the kernels' shared library (pipelines/common/cl_library.hpp).

// ---- Tracking in the voxel medium with per-brick majorants -----------------------------------

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
// crosses there is walked voxel by voxel instead, each voxel's own sigma being an exact majorant:
// a brick that holds a dense blocker (sigma up to 1e6) beside a thin medium would otherwise take
// majorant / sigma null collisions per real one (seconds per pixel).
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

// Delta tracking: the first real collision along o + t d, t < tmax, for `channel`. Empty bricks
// are stepped over; within a brick, tentative collisions are drawn with the brick's majorant, or
// (walk_voxels) exactly per voxel.
bool delta_track(const Grid* g, __global const float* sigma_t, __global const float* majorant,
                 int channel, float3 o, float3 d, float tmax, Rng* r, float* t_hit) {
  Dda s;
  if (!brick_walk(g, o, d, tmax, &s)) return false;
  float a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    float m = majorant[(c.z * g->by + c.y) * g->bx + c.x];
    if (m <= 0.0f) continue;
    if (walk_voxels(g, m, a, b)) {
      Dda v;
      dda_init(&v, o, d, g->origin, g->voxel, (int3)(g->nx, g->ny, g->nz), a, b);
      float va, vb;
      int3 vc;
      while (dda_next(&v, &va, &vb, &vc)) {
        float sig = voxel_sigma(g, sigma_t, vc, channel);
        if (sig <= 0.0f) continue;
        float t = va - log(1.0f - rng_uniform(r)) / sig;
        if (t < vb) {
          *t_hit = t;
          return true;
        }
      }
      continue;
    }
    for (float t = next_tentative(a, m, b, r); t < b; t = next_tentative(t, m, b, r)) {
      float sig = voxel_sigma(g, sigma_t, voxel_of(g, o + d * t), channel);
      if (rng_uniform(r) * m < sig) {
        *t_hit = t;
        return true;
      }
    }
  }
  return false;
}

// Ratio tracking: an unbiased estimate of the transmittance along o + t d, t in [0, tmax], with
// Russian roulette once it is small so dense media end early. A brick walked voxel by voxel
// (walk_voxels) contributes its exact transmittance.
float ratio_track(const Grid* g, __global const float* sigma_t, __global const float* majorant,
                  int channel, float3 o, float3 d, float tmax, Rng* r) {
  Dda s;
  if (!brick_walk(g, o, d, tmax, &s)) return 1.0f;
  float tr = 1.0f, a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    float m = majorant[(c.z * g->by + c.y) * g->bx + c.x];
    if (m <= 0.0f) continue;
    if (walk_voxels(g, m, a, b)) {
      Dda v;
      dda_init(&v, o, d, g->origin, g->voxel, (int3)(g->nx, g->ny, g->nz), a, b);
      float va, vb, tau = 0.0f;
      int3 vc;
      while (dda_next(&v, &va, &vb, &vc)) tau += voxel_sigma(g, sigma_t, vc, channel) * (vb - va);
      tr *= exp(-tau);
    } else {
      for (float t = next_tentative(a, m, b, r); t < b; t = next_tentative(t, m, b, r))
        tr *= 1.0f - voxel_sigma(g, sigma_t, voxel_of(g, o + d * t), channel) / m;
    }
    if (tr < 0.01f) {
      if (tr <= 0.0f || rng_uniform(r) >= 0.5f) return 0.0f;
      tr *= 2.0f;
    }
  }
  return tr;
}
