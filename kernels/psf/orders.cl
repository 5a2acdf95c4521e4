// The `psf` pipeline's `orders` model (model 1; pipelines/psf/orders.hpp): the light scattered
// m = 1, 2, ... times, order by order on a coarse level of the light pyramid. The source of order
// m is q_m (scattered power per volume; q_1 = b * L0, the pyramid's level); its light spreads by
// the m-th flight's Gaussians (pyramid.cl: blur_axis, per channel, summed by add_scaled) and
// drifts along the light's direction (order_step), giving the fluence
// phi_m = blur(q_m)(x + drift * wl) / c_mean; phi_m is added to its band and q_(m+1) = b(x) phi_m
// (zero where there is no medium: light that leaves does not come back). With `conserve` (the
// default) b is b_eff and q_m is scaled first (order_scale) so that each flight's collisions take
// what stays inside the mesh; without, b is capped (coarse_sigma). Volumes are float4 per voxel
// (RGB, 0), x fastest. After pyramid.cl and march.cl.

// The coarse level's scattering coefficient for the next order's source: b and c averaged over
// 2^level voxels of the source grid (clipped at its edge), b capped at the albedo times c_mean.
// The flights carry light one mean free path 1 / c_mean everywhere, so a voxel denser than the
// mean collides with no more than all of it: each order keeps at most its albedo of the power.
__kernel void coarse_sigma(__global const float* sigma_s, __global const float* sigma_t, int nx,
                           int ny, int nz, int level, float4 c_mean, __global float4* out, int ox,
                           int oy, int oz) {
  int i = get_global_id(0), j = get_global_id(1), k = get_global_id(2);
  if (i >= ox || j >= oy || k >= oz) return;
  int n = 1 << level;
  float3 s = (float3)(0.0f), t = (float3)(0.0f);
  int count = 0;
  for (int z = k * n; z < min((k + 1) * n, nz); ++z)
    for (int y = j * n; y < min((j + 1) * n, ny); ++y)
      for (int x = i * n; x < min((i + 1) * n, nx); ++x) {
        s += vload3((z * ny + y) * nx + x, sigma_s);
        t += vload3((z * ny + y) * nx + x, sigma_t);
        ++count;
      }
  s /= (float)max(count, 1);
  t /= (float)max(count, 1);
  float3 albedo = select(s / t, (float3)(0.0f), isless(t, 1e-30f));
  out[(k * oy + j) * ox + i] = (float4)(fmin(s, albedo * c_mean.xyz), 0.0f);
}

// `conserve` (the default): the coarse level's collision and scattering coefficients. Per source
// voxel c_eff = (1 - exp(-c dl)) / dl, the chance of colliding while crossing dl (the coarse
// cell) per length (c in thin voxels, at most 1 / dl in opaque ones), and b_eff = c_eff b / c,
// both averaged over the 2^level voxels as is the occupancy (the share inside the mesh).
__kernel void coarse_collision(__global const float* sigma_s, __global const float* sigma_t,
                               __global const float* occupancy, int nx, int ny, int nz, int level,
                               float dl, __global float4* b_out, __global float4* c_out,
                               __global float4* occ_out, int ox, int oy, int oz) {
  int i = get_global_id(0), j = get_global_id(1), k = get_global_id(2);
  if (i >= ox || j >= oy || k >= oz) return;
  int n = 1 << level;
  float3 b = (float3)(0.0f), c = (float3)(0.0f);
  float occ = 0.0f;
  int count = 0;
  for (int z = k * n; z < min((k + 1) * n, nz); ++z)
    for (int y = j * n; y < min((j + 1) * n, ny); ++y)
      for (int x = i * n; x < min((i + 1) * n, nx); ++x) {
        int v = (z * ny + y) * nx + x;
        float3 t = vload3(v, sigma_t), u = t * dl;
        float3 ce = select((1.0f - exp(-u)) / dl, t * (1.0f - 0.5f * u), isless(u, 1e-4f));
        b += select(ce * vload3(v, sigma_s) / t, (float3)(0.0f), isless(t, 1e-30f));
        c += ce;
        occ += occupancy[v];
        ++count;
      }
  float inv = 1.0f / (float)max(count, 1);
  int o = (k * oy + j) * ox + i;
  b_out[o] = (float4)(b * inv, 0.0f);
  c_out[o] = (float4)(c * inv, 0.0f);
  occ_out[o] = (float4)((float3)(occ * inv), 0.0f);
}

// `conserve`: the factor by which a source voxel's light is scaled before its flight, so that
// what the flight's collisions take, sum over y of c_eff(y) phi(y), is the share of the flight
// that stays inside the mesh: E c_mean / N, where N = K * c_eff and E = K * occupancy (the
// flight's kernel K, blurred by the host) are read where the flight lands, `drift` (world units,
// per channel) downstream from the light. Zero where the flight reaches no medium.
__kernel void order_scale(__global const float4* n_blur, __global const float4* e_blur, int nx,
                          int ny, int nz, float3 origin, float cell, __global const float* lights,
                          int light, float4 drift, float4 c_mean, __global float4* scale) {
  int i = get_global_id(0), j = get_global_id(1), k = get_global_id(2);
  if (i >= nx || j >= ny || k >= nz) return;
  int v = (k * ny + j) * nx + i;
  float3 x = origin + cell * ((float3)(i, j, k) + 0.5f);
  float4 nb = n_blur[v], eb = e_blur[v];
  if (drift.x != 0.0f || drift.y != 0.0f || drift.z != 0.0f) {
    Light L = load_light(lights, light);
    float3 wl;
    float dist;
    light_irradiance(L, x, 0, &wl, &dist);
    nb.x = trilinear(n_blur, 0, nx, ny, nz, origin, cell, x - drift.x * wl).x;
    nb.y = trilinear(n_blur, 0, nx, ny, nz, origin, cell, x - drift.y * wl).y;
    nb.z = trilinear(n_blur, 0, nx, ny, nz, origin, cell, x - drift.z * wl).z;
    eb.x = trilinear(e_blur, 0, nx, ny, nz, origin, cell, x - drift.x * wl).x;
    eb.y = trilinear(e_blur, 0, nx, ny, nz, origin, cell, x - drift.y * wl).y;
    eb.z = trilinear(e_blur, 0, nx, ny, nz, origin, cell, x - drift.z * wl).z;
  }
  float3 s = select((float3)(0.0f), eb.xyz * c_mean.xyz / nb.xyz,
                    isgreater(nb.xyz, fmax(1e-6f * c_mean.xyz, 1e-30f)));
  scale[v] = (float4)(s, 0.0f);
}

// x *= s, per voxel and channel.
__kernel void scale_by(__global float4* x, __global const float4* s, int count) {
  int i = get_global_id(0);
  if (i >= count) return;
  x[i] *= s[i];
}

// acc = (first ? 0 : acc) + w * x: the flight's Gaussians summed with their weights.
__kernel void add_scaled(__global float4* acc, __global const float4* x, float w, int first,
                         int count) {
  int i = get_global_id(0);
  if (i >= count) return;
  acc[i] = (first ? (float4)(0.0f) : acc[i]) + w * x[i];
}

// The orders past the last one computed, once each order is the one before times lambda (the
// slowest-decaying mode has taken over): sum_{k>=1} lambda^k phi_m into the rest's band and
// sum_{k>=1} g^(m+1+k) lambda^k phi_m into its phase moment.
__kernel void add_tail(__global float4* bands, __global const float4* last, float4 rest,
                       float4 moment, int count) {
  int v = get_global_id(0);
  if (v >= count) return;
  bands[4 * v + 2] += rest * last[v];
  bands[4 * v + 3] += moment * last[v];
}

// phi_m = blurred q_m read `drift` (world units, per channel) upstream towards the light, over
// c_mean; added to band `band` (0: order 1, 1: order 2, 2: the rest, whose band 3 holds the sum of
// g^(m+1) phi_m for its phase); q_next = b * phi_m. bands: 4 float4 per voxel.
__kernel void order_step(__global const float4* blurred, __global const float4* sigma_s, int nx,
                         int ny, int nz, float3 origin, float cell, __global const float* lights,
                         int light, float4 drift, float4 inv_c, int band, float4 g_next,
                         __global float4* bands, __global float4* q_next,
                         __global float4* phi_out) {
  int i = get_global_id(0), j = get_global_id(1), k = get_global_id(2);
  if (i >= nx || j >= ny || k >= nz) return;
  int v = (k * ny + j) * nx + i;
  float3 x = origin + cell * ((float3)(i, j, k) + 0.5f);
  float4 phi;
  if (drift.x == 0.0f && drift.y == 0.0f && drift.z == 0.0f) {
    phi = blurred[v];
  } else {
    Light L = load_light(lights, light);
    float3 wl;
    float dist;
    light_irradiance(L, x, 0, &wl, &dist);
    phi.x = trilinear(blurred, 0, nx, ny, nz, origin, cell, x + drift.x * wl).x;
    phi.y = trilinear(blurred, 0, nx, ny, nz, origin, cell, x + drift.y * wl).y;
    phi.z = trilinear(blurred, 0, nx, ny, nz, origin, cell, x + drift.z * wl).z;
    phi.w = 0.0f;
  }
  phi *= inv_c;
  bands[4 * v + band] += phi;
  if (band == 2) bands[4 * v + 3] += g_next * phi;
  q_next[v] = sigma_s[v] * phi;
  phi_out[v] = phi;
}
