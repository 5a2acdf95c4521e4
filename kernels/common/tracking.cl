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

// Delta tracking: the first real collision along o + t d, t < tmax, for `channel`. Empty bricks
// are stepped over; within a brick, tentative collisions are drawn with the brick's majorant.
bool delta_track(const Grid* g, __global const float* sigma_t, __global const float* majorant,
                 int channel, float3 o, float3 d, float tmax, Rng* r, float* t_hit) {
  Dda s;
  if (!brick_walk(g, o, d, tmax, &s)) return false;
  float a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    float m = majorant[(c.z * g->by + c.y) * g->bx + c.x];
    if (m <= 0.0f) continue;
    float t = a;
    for (;;) {
      t -= log(1.0f - rng_uniform(r)) / m;
      if (t >= b) break;
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
// Russian roulette once it is small so dense media end early.
float ratio_track(const Grid* g, __global const float* sigma_t, __global const float* majorant,
                  int channel, float3 o, float3 d, float tmax, Rng* r) {
  Dda s;
  if (!brick_walk(g, o, d, tmax, &s)) return 1.0f;
  float tr = 1.0f, a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    float m = majorant[(c.z * g->by + c.y) * g->bx + c.x];
    if (m <= 0.0f) continue;
    float t = a;
    for (;;) {
      t -= log(1.0f - rng_uniform(r)) / m;
      if (t >= b) break;
      tr *= 1.0f - voxel_sigma(g, sigma_t, voxel_of(g, o + d * t), channel) / m;
      if (tr < 0.01f) {
        if (tr <= 0.0f || rng_uniform(r) >= 0.5f) return 0.0f;
        tr *= 2.0f;
      }
    }
  }
  return tr;
}
