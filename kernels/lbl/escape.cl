// The escape correction's exact part (pipelines/lbl/escape): per voxel, the chance that light
// emitted isotropically at its centre leaves the grid without another interaction (its own
// voxel's depth weighted: see below), the mean of
// exp(-tau) over `count` directions (tau through the delta-Eddington scaled sigma_t', RGB; exact
// voxel crossings, a ray stopped once all channels pass tau 6). Voxels that do not scatter get 1.
// `escape_samples` computes it at every `stride`-th voxel (a listed subset), and
// `escape_interpolate` fills every voxel from them or computes it there.

bool escape_scatters(__global const float* sigma_s, int v) {
  return sigma_s[v] > 0.0f || sigma_s[v + 1] > 0.0f || sigma_s[v + 2] > 0.0f;
}

// Adds to tau the optical depth along o + t d over [t0, t1] through `grid` (cell = its voxel);
// the voxel `own` (of a fine grid) counts its depth times exp(-sigma_t' dx): the lattice sends a
// node's emission to its neighbours whole, so all of it counts when the voxel is thin, none when
// it is dense (whose own depth would make P far below the lattice's, and m amplify).
float3 escape_depth(const Grid* grid, __global const float* sigma_t, int3 own, float3 o, float3 d,
                    float t0, float t1, float3 tau) {
  Dda s;
  dda_init(&s, o, d, grid->origin, grid->voxel, (int3)(grid->nx, grid->ny, grid->nz), t0, t1);
  float a, b;
  int3 q;
  while (fmin(tau.x, fmin(tau.y, tau.z)) < 6.0f && dda_next(&s, &a, &b, &q)) {
    int w = 3 * voxel_index(grid, q.x, q.y, q.z);
    float3 st = (float3)(sigma_t[w], sigma_t[w + 1], sigma_t[w + 2]);
    if (q.x == own.x && q.y == own.y && q.z == own.z) st *= exp(-st * grid->voxel);
    tau += (b - a) * st;
  }
  return tau;
}

// The grid of 2 x 2 x 2 voxels per cell over g ((n + 1) / 2 cells per side).
Grid half_grid(const Grid* g) {
  return make_grid(g->origin, 2.0f * g->voxel, (g->nx + 1) / 2, (g->ny + 1) / 2, (g->nz + 1) / 2,
                   1, 0, 0, 0);
}

// The voxel of sample s of an (sx, sy, sz) grid of samples at every stride-th voxel.
int3 sample_voxel(int s, int stride, int sx, int sy) {
  return stride * (int3)(s % sx, (s / sx) % sy, s / (sx * sy));
}

// At voxel c, the trilinear mean over the samples around it (3 floats a sample, that grid) of x,
// or with `logs` of log x; every sample with weight must be there (pipelines/lbl/escape.cpp).
float3 sample_trilinear(__global const float* samples, int3 c, int stride, int sx, int sy,
                        int logs) {
  int3 s0 = c / stride;
  float3 f = convert_float3(c - stride * s0) / (float)stride;
  float3 sum = (float3)(0.0f);
  for (int corner = 0; corner < 8; ++corner) {
    int3 o = (int3)(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
    float3 t = select(1.0f - f, f, o == 1);
    float wc = t.x * t.y * t.z;
    if (wc <= 0.0f) continue;
    int3 s = s0 + o;
    float3 x = vload3((s.z * sy + s.y) * sx + s.x, samples);
    sum += wc * (logs ? log(fmax(x, 1e-30f)) : x);
  }
  return sum;
}

// The trilinear mean of log x over the samples around voxel c, exponentiated.
float3 log_trilinear(__global const float* samples, int3 c, int stride, int sx, int sy) {
  return exp(sample_trilinear(samples, c, stride, sx, sy, 1));
}

// The mean of exp(-tau) over the directions from the centre of voxel c. With far > 0 a ray
// crosses the fine voxels for its first `far` voxel widths and then the `coarse` grid (2x2x2
// voxels per cell, their mean sigma_t'): about half the steps, the same depth on average.
float3 escape_at(const Grid* g, int3 c, __global const float* sigma_t, const Grid* cg,
                 __global const float* coarse, float far, __global const float* dirs, int count) {
  float3 o = g->origin + g->voxel * (convert_float3(c) + 0.5f);
  float3 sum = (float3)(0.0f);
  for (int k = 0; k < count; ++k) {
    float3 d = (float3)(dirs[3 * k], dirs[3 * k + 1], dirs[3 * k + 2]);
    float t0, t1;
    float3 tau = (float3)(0.0f);
    if (grid_interval(g, o, d, &t0, &t1)) {
      float tf = far > 0.0f ? fmin(t1, t0 + far * g->voxel) : t1;
      tau = escape_depth(g, sigma_t, c, o, d, t0, tf, tau);
      if (tf < t1) tau = escape_depth(cg, coarse, (int3)(-1), o, d, tf, t1, tau);
    }
    sum += exp(-tau);
  }
  return sum / (float)count;
}

__kernel void escape_exact(float3 origin, float voxel, int nx, int ny, int nz,
                           __global const float* sigma_t, __global const float* sigma_s,
                           __global const float* dirs, int count, __global float* out) {
  int3 c = (int3)(get_global_id(0), get_global_id(1), get_global_id(2));
  if (c.x >= nx || c.y >= ny || c.z >= nz) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  int v = 3 * voxel_index(&g, c.x, c.y, c.z);
  float3 p = escape_scatters(sigma_s, v) ? escape_at(&g, c, sigma_t, &g, sigma_t, 0.0f, dirs, count)
                                         : (float3)(1.0f);
  out[v] = p.x;
  out[v + 1] = p.y;
  out[v + 2] = p.z;
}

// P at the listed samples: sample (a, b, c) of an (sx, sy, sz) grid sits at voxel stride (a, b, c).
__kernel void escape_samples(float3 origin, float voxel, int nx, int ny, int nz,
                             __global const float* sigma_t, __global const float* coarse,
                             float far, __global const float* dirs, int count, int stride, int sx,
                             int sy, __global const int* list, int listed,
                             __global float* samples) {
  int id = get_global_id(0);
  if (id >= listed) return;
  int s = list[id];
  int3 c = sample_voxel(s, stride, sx, sy);
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  Grid cg = half_grid(&g);
  float3 p = escape_at(&g, c, sigma_t, &cg, coarse, far, dirs, count);
  samples[3 * s] = p.x;
  samples[3 * s + 1] = p.y;
  samples[3 * s + 2] = p.z;
}

// Every voxel by its mode (pipelines/lbl/escape.cpp): 0 does not scatter (P 1), 1 the trilinear
// mean of the samples around it (each one listed), 2 computed at the voxel itself.
__kernel void escape_interpolate(float3 origin, float voxel, int nx, int ny, int nz,
                                 __global const float* sigma_t, __global const float* coarse,
                                 float far, __global const char* mode,
                                 __global const float* dirs, int count, int stride, int sx, int sy,
                                 __global const float* samples, __global float* out) {
  int3 c = (int3)(get_global_id(0), get_global_id(1), get_global_id(2));
  if (c.x >= nx || c.y >= ny || c.z >= nz) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  int i = voxel_index(&g, c.x, c.y, c.z);
  float3 p = (float3)(1.0f);
  if (mode[i] == 2) {
    Grid cg = half_grid(&g);
    p = escape_at(&g, c, sigma_t, &cg, coarse, far, dirs, count);
  } else if (mode[i] == 1) {
    p = log_trilinear(samples, c, stride, sx, sy);
  }
  out[3 * i] = p.x;
  out[3 * i + 1] = p.y;
  out[3 * i + 2] = p.z;
}
