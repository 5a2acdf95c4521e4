// Monte Carlo volumetric path tracer (index-matched boundary): delta tracking in the voxel medium
// with per-brick majorants, next-event estimation to every light with ratio-tracked shadow rays,
// Henyey-Greenstein sampling, Russian roulette on the path weight. One colour channel per sample
// (cycled), weighted by 3, so chromatic media need no spectral majorants.
//
// terms: bit 0 adds light scattered once (NEE at the first vertex), bit 1 light scattered more
// than once. Each launch adds `spp` samples per pixel to sum and sum_sq (per channel, the squared
// per-sample values), from which the host takes the mean and its standard error.

__kernel void path_trace(float3 origin, float voxel, int nx, int ny, int nz, int brick, int bx,
                         int by, int bz, __global const float* sigma_s,
                         __global const float* sigma_t, __global const float* majorant,
                         __global const float* lights, int light_count, float g_phase,
                         __global const float* camera, int width, int height, int terms,
                         int spp, int first_sample, uint seed, int max_depth,
                         __global float* sum, __global float* sum_sq) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  Grid g;
  g.origin = origin;
  g.voxel = voxel;
  g.nx = nx;
  g.ny = ny;
  g.nz = nz;
  g.brick = brick;
  g.bx = bx;
  g.by = by;
  g.bz = bz;
  Cam cam = load_camera(camera);
  float3 d0 = camera_ray(cam, x, y, width, height, 0.5f, 0.5f);
  float acc[3] = {0, 0, 0}, acc2[3] = {0, 0, 0};
  for (int s = 0; s < spp; ++s) {
    int sample = first_sample + s;
    int ch = sample % 3;
    Rng r = rng_seed((uint)(y * width + x), (uint)sample, seed);
    float3 o = cam.position, d = d0;
    float weight = 1.0f, value = 0.0f;
    for (int depth = 1; depth <= max_depth; ++depth) {
      float t;
      if (!delta_track(&g, sigma_t, majorant, ch, o, d, INFINITY, &r, &t)) break;
      o = o + d * t;
      int v = 3 * voxel_index(&g, voxel_of(&g, o).x, voxel_of(&g, o).y, voxel_of(&g, o).z) + ch;
      float st = sigma_t[v];
      weight *= st > 0.0f ? sigma_s[v] / st : 0.0f;
      if (weight <= 0.0f) break;
      bool wanted = (depth == 1 && (terms & 1)) || (depth > 1 && (terms & 2));
      if (wanted) {
        for (int l = 0; l < light_count; ++l) {
          float3 wl;
          float dist;
          float e = light_irradiance(load_light(lights, l), o, ch, &wl, &dist);
          if (e <= 0.0f) continue;
          float tr = ratio_track(&g, sigma_t, majorant, ch, o, wl, dist, &r);
          value += weight * e * tr * hg_phase(dot(wl, d), g_phase);
        }
      }
      if (!(terms & 2)) break;  // single scattering only: the path ends at its first vertex
      d = hg_sample(d, g_phase, &r);
      if (depth >= 3 && weight < 0.25f) {  // Russian roulette on the path weight
        float q = fmax(weight, 0.05f);
        if (rng_uniform(&r) >= q) break;
        weight /= q;
      }
    }
    float contribution = 3.0f * value;
    acc[ch] += contribution;
    acc2[ch] += contribution * contribution;
  }
  size_t i = 3 * ((size_t)y * width + x);
  for (int c = 0; c < 3; ++c) {
    sum[i + c] += acc[c];
    sum_sq[i + c] += acc2[c];
  }
}
