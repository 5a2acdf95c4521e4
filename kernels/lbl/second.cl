// The light's second scattering, computed exactly (pipelines/lbl/second): the lattice then
// carries only the third and later events. Per voxel x, what the once-scattered light scatters
// there, in the delta-Eddington scaled medium the lattice works in (sigma_t' = sigma_t -
// g sigma_s, sigma_s' = (1 - g) sigma_s, isotropic):
//   Q2(x) = sigma_s'(x) phi1(x) V,  phi1(x) = (1 / K) sum_k integral_0^inf q1(x + s d_k) T(x, s) ds
// (the fluence of light emitted isotropically with density q1 = source / V, over K directions
// d_k, each weighing 4 pi / K): power per voxel, as the source is (V cancels: the source's power
// per voxel stands for q1 V). Along each direction the voxels are crossed exactly (DDA); a voxel
// y crossed over [a, b] adds q1(y) V exp(-tau(a)) (1 - exp(-sigma_t'(y) (b - a))) / sigma_t'(y).
// The gather also keeps m(x), the mean direction that light travels in (its net flux over its
// fluence, channels summed: sum_k -d_k x its light along d_k over the light): the view scatters
// Q2 towards the eye about m (kernels/lbl/view.cl). A ray stops once all channels pass an optical depth of 8 (what it leaves out is under
// exp(-8) of its sum). As the escape correction (kernels/lbl/escape.cl): with far > 0 a ray
// crosses the fine voxels for `far` voxel widths and then the coarse grid (2 x 2 x 2 voxels per
// cell, their mean sigma_t' and source); `second_samples` computes phi1 at every stride-th voxel
// (a listed subset), `second_interpolate` fills every voxel from them or computes it there.
// Built after kernels/lbl/escape.cl (sample_voxel, sample_trilinear, log_trilinear).

// Adds to *sum the source's light along o + t d over [t0, t1] through `grid`, and to *tau the
// optical depth crossed.
void second_along(const Grid* grid, __global const float* sigma_t, __global const float* source,
                  float3 o, float3 d, float t0, float t1, float3* tau, float3* sum) {
  Dda s;
  dda_init(&s, o, d, grid->origin, grid->voxel, (int3)(grid->nx, grid->ny, grid->nz), t0, t1);
  float a, b;
  int3 q;
  while (fmin(tau->x, fmin(tau->y, tau->z)) < 8.0f && dda_next(&s, &a, &b, &q)) {
    int w = 3 * voxel_index(grid, q.x, q.y, q.z);
    float3 st = (float3)(sigma_t[w], sigma_t[w + 1], sigma_t[w + 2]);
    float3 q1 = (float3)(source[w], source[w + 1], source[w + 2]);
    float len = b - a;
    float3 x = st * len;
    // (1 - exp(-x)) / sigma_t', which tends to len for a thin piece.
    float3 piece = select(-expm1(-x) / st, (float3)(len), x < 1e-4f);
    *sum += q1 * exp(-*tau) * piece;
    *tau += x;
  }
}

// phi1 V at the centre of voxel c: the mean over the directions of the light arriving there;
// *m the mean direction that light travels in (its channels summed), |m| <= 1.
float3 second_at(const Grid* g, int3 c, __global const float* sigma_t,
                 __global const float* source, const Grid* cg, __global const float* coarse_t,
                 __global const float* coarse_source, float far, __global const float* dirs,
                 int count, float3* m) {
  float3 o = g->origin + g->voxel * (convert_float3(c) + 0.5f);
  float3 sum = (float3)(0.0f), flux = (float3)(0.0f);
  for (int k = 0; k < count; ++k) {
    float3 d = (float3)(dirs[3 * k], dirs[3 * k + 1], dirs[3 * k + 2]);
    float t0, t1;
    if (!grid_interval(g, o, d, &t0, &t1)) continue;
    float3 tau = (float3)(0.0f), along = (float3)(0.0f);
    float tf = far > 0.0f ? fmin(t1, t0 + far * g->voxel) : t1;
    second_along(g, sigma_t, source, o, d, t0, tf, &tau, &along);
    if (tf < t1) second_along(cg, coarse_t, coarse_source, o, d, tf, t1, &tau, &along);
    sum += along;
    flux -= d * (along.x + along.y + along.z);  // the light from o + s d travels along -d
  }
  float total = sum.x + sum.y + sum.z;
  *m = total > 0.0f ? flux / total : (float3)(0.0f);
  return sum / (float)count;
}

// The mean of the 8 voxels of each coarse cell (3 channels; voxels past the high end count 0).
__kernel void second_coarse(int nx, int ny, int nz, __global const float* fine,
                            __global float* coarse) {
  int3 c = (int3)(get_global_id(0), get_global_id(1), get_global_id(2));
  int cx = (nx + 1) / 2, cy = (ny + 1) / 2, cz = (nz + 1) / 2;
  if (c.x >= cx || c.y >= cy || c.z >= cz) return;
  float3 sum = (float3)(0.0f);
  for (int o = 0; o < 8; ++o) {
    int3 q = 2 * c + (int3)(o & 1, (o >> 1) & 1, (o >> 2) & 1);
    if (q.x >= nx || q.y >= ny || q.z >= nz) continue;
    sum += vload3((q.z * ny + q.y) * nx + q.x, fine);
  }
  vstore3(sum / 8.0f, (c.z * cy + c.y) * cx + c.x, coarse);
}

// phi1 V at the listed samples: sample (a, b, c) of an (sx, sy, sz) grid sits at voxel
// stride (a, b, c).
__kernel void second_samples(float3 origin, float voxel, int nx, int ny, int nz,
                             __global const float* sigma_t, __global const float* source,
                             __global const float* coarse_t, __global const float* coarse_source,
                             float far, __global const float* dirs, int count, int stride,
                             int sx, int sy, __global const int* list, int listed,
                             __global float* samples, __global float* msamples) {
  int id = get_global_id(0);
  if (id >= listed) return;
  int s = list[id];
  int3 c = sample_voxel(s, stride, sx, sy);
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  Grid cg = half_grid(&g);
  float3 m;
  vstore3(second_at(&g, c, sigma_t, source, &cg, coarse_t, coarse_source, far, dirs, count, &m), s,
          samples);
  vstore3(m, s, msamples);
}

// Q2 = sigma_s' phi1 V at every voxel by its mode (pipelines/lbl/escape.cpp's sampling): 0 does
// not scatter (0), 1 the trilinear mean of log phi1 over the samples around it (each one listed), 2 computed
// at the voxel itself.
__kernel void second_interpolate(float3 origin, float voxel, int nx, int ny, int nz,
                                 __global const float* sigma_t, __global const float* source,
                                 __global const float* coarse_t,
                                 __global const float* coarse_source, float far,
                                 __global const char* mode, __global const float* dirs, int count,
                                 int stride, int sx, int sy, __global const float* samples,
                                 __global const float* msamples, __global const float* sigma_s,
                                 float g, __global float* out, __global float* mout) {
  int3 c = (int3)(get_global_id(0), get_global_id(1), get_global_id(2));
  if (c.x >= nx || c.y >= ny || c.z >= nz) return;
  Grid grid = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  int i = voxel_index(&grid, c.x, c.y, c.z);
  float3 phi = (float3)(0.0f), m = (float3)(0.0f);
  if (mode[i] == 2) {
    Grid cg = half_grid(&grid);
    phi = second_at(&grid, c, sigma_t, source, &cg, coarse_t, coarse_source, far, dirs, count, &m);
  } else if (mode[i] == 1) {
    phi = log_trilinear(samples, c, stride, sx, sy);
    m = sample_trilinear(msamples, c, stride, sx, sy, 0);
  }
  vstore3((1.0f - g) * vload3(i, sigma_s) * phi, i, out);
  vstore3(m, i, mout);
}

// The next order on a coarser grid (setting `gathers`, pipelines/lbl/second.cpp): phi V at the
// listed cells' centres of the (cx, cy, cz) grid of side `cell` (each cell the mean of the
// voxels it covers: second_coarse, applied once per halving), from its source through its mean
// sigma_t', every ray on that grid.
__kernel void second_coarse_gather(float3 origin, float cell, int cx, int cy, int cz,
                                   __global const float* coarse_t,
                                   __global const float* coarse_source, __global const float* dirs,
                                   int count, __global const int* list, int listed,
                                   __global float* coarse_phi) {
  int id = get_global_id(0);
  if (id >= listed) return;
  Grid cg = make_grid(origin, cell, cx, cy, cz, 1, 0, 0, 0);
  int s = list[id];
  int3 c = (int3)(s % cx, (s / cx) % cy, s / (cx * cy));
  float3 m;
  vstore3(second_at(&cg, c, coarse_t, coarse_source, &cg, coarse_t, coarse_source, 0.0f, dirs,
                    count, &m),
          s, coarse_phi);
}

// The next order per voxel from the coarse cells' phi V (`factor` voxels a cell per axis),
// trilinear between the cells' centres (clamped at the grid's ends): out = sigma_s' phi V, and
// sum += out.
__kernel void second_from_coarse(int nx, int ny, int nz, int factor, int cx, int cy, int cz,
                                 __global const float* coarse_phi, __global const float* sigma_s,
                                 float g, __global float* out, __global float* sum) {
  int3 c = (int3)(get_global_id(0), get_global_id(1), get_global_id(2));
  if (c.x >= nx || c.y >= ny || c.z >= nz) return;
  int i = (c.z * ny + c.y) * nx + c.x;
  float3 ss = vload3(i, sigma_s);
  float3 q = (float3)(0.0f);
  if (ss.x > 0.0f || ss.y > 0.0f || ss.z > 0.0f) {
    int3 cn = (int3)(cx, cy, cz);
    // Voxel centre i + 1/2 sits at (i + 1/2) / factor - 1/2 in the cells' centre coordinates.
    float3 u = clamp((convert_float3(c) + 0.5f) / (float)factor - 0.5f, (float3)(0.0f),
                     convert_float3(cn - 1));
    int3 c0 = min(convert_int3(u), cn - 1), c1 = min(c0 + 1, cn - 1);
    float3 f = u - convert_float3(c0);
    float3 phi = (float3)(0.0f);
    for (int o = 0; o < 8; ++o) {
      int3 b = (int3)(o & 1, (o >> 1) & 1, (o >> 2) & 1);
      int3 q3 = select(c0, c1, b == 1);
      float3 w3 = select(1.0f - f, f, b == 1);
      phi += w3.x * w3.y * w3.z * vload3((q3.z * cy + q3.y) * cx + q3.x, coarse_phi);
    }
    q = (1.0f - g) * ss * phi;
  }
  vstore3(q, i, out);
  vstore3(vload3(i, sum) + q, i, sum);
}
