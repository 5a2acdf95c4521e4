// Light marching: each work item carries one light ray (start just outside the medium, unit
// direction, RGB power in watts) through the material volume and deposits, in every voxel it
// crosses, the power scattered there out of the ray. For a piece of path of length ds inside a
// voxel with coefficients sigma_s, sigma_t and power P entering it (Beer-Lambert):
//   scattered  P (sigma_s / sigma_t) (1 - exp(-sigma_t ds))
//   remaining  P exp(-sigma_t ds)
// Straight rays (constant n) cross the voxels exactly (DDA); bent rays take fixed steps of the
// ray equation (coefficients of the voxel holding the step's midpoint). The scattered power is
// splatted trilinearly around the piece's midpoint; deposits from concurrent rays add through a
// compare-and-swap loop (atomic_add_float). With an anisotropic phase (with_flow) the scattered
// power summed over channels times the ray's unit direction is splatted the same way into `flow`
// (3 floats per voxel): the view pass takes the single term's phase about its mean direction;
// after those (flow + 3 N) the forward-scattered light's scattering (`extra`, RGB per voxel).

// A ray record: origin (3), unit direction (3), power (3), unused (3).
#define RAY_FLOATS 12

// Adds `amount` at p spread over the 8 voxels around it with trilinear weights (centres clamped
// to the grid), kept only on the voxels that scatter in channel `mask_ch` (any channel when -1)
// and renormalised over them: a regular lattice of rays then deposits evenly instead of beating
// against the voxel lattice, and nothing lands in the empty voxels outside the surface (which
// the view pass would see glow). The voxel the piece lies in always scatters, so the sum is > 0.
void splat(const Grid* g, __global const float* sigma_s, int mask_ch, float3 p, int ch,
           float amount, __global float* deposit) {
  float3 q = clamp((p - g->origin) / g->voxel - 0.5f, (float3)(0.0f),
                   (float3)(g->nx - 1, g->ny - 1, g->nz - 1));
  int3 c0 = convert_int3(floor(q));
  int3 c1 = min(c0 + 1, (int3)(g->nx - 1, g->ny - 1, g->nz - 1));
  float3 f = q - convert_float3(c0);
  float w[8], total = 0.0f;
  int idx[8];
  for (int corner = 0; corner < 8; ++corner) {
    int3 c = (int3)((corner & 1) ? c1.x : c0.x, (corner & 2) ? c1.y : c0.y, (corner & 4) ? c1.z : c0.z);
    idx[corner] = voxel_index(g, c.x, c.y, c.z);
    int v = 3 * idx[corner];
    bool scatters = mask_ch < 0 ? (sigma_s[v] > 0.0f || sigma_s[v + 1] > 0.0f || sigma_s[v + 2] > 0.0f)
                                : sigma_s[v + mask_ch] > 0.0f;
    w[corner] = scatters ? ((corner & 1) ? f.x : 1.0f - f.x) * ((corner & 2) ? f.y : 1.0f - f.y) *
                               ((corner & 4) ? f.z : 1.0f - f.z)
                         : 0.0f;
    total += w[corner];
  }
  if (!(total > 0.0f)) return;
  for (int corner = 0; corner < 8; ++corner)
    if (w[corner] > 0.0f) atomic_add_float(deposit + 3 * idx[corner] + ch, w[corner] / total * amount);
}

// Beer-Lambert over a piece of length ds in voxel c; the scattered power is splatted at `mid`.
// With g != 0 a second, delta-Eddington scaled beam feeds the lattice: the forward fraction g of
// its scattering stays in the beam (sigma_s' = (1 - g) sigma_s), as the lattice's own
// coefficients are scaled, and what it scatters goes to `source`; `deposit` keeps the real
// single scattering for the view pass.
void deposit_piece(const Grid* g, __global const float* sigma_s, __global const float* sigma_t,
                   float g_phase, int3 c, float3 mid, float3 dir, float ds, float3* power,
                   float3* scaled, __global float* deposit, __global float* source,
                   __global float* flow, int with_flow) {
  int v = 3 * voxel_index(g, c.x, c.y, c.z);
  float p[3] = {power->x, power->y, power->z}, q[3] = {scaled->x, scaled->y, scaled->z};
  float total = 0.0f;
  __global float* extra = flow + 3 * g->nx * g->ny * g->nz;
  for (int ch = 0; ch < 3; ++ch) {
    float st = sigma_t[v + ch], ss = sigma_s[v + ch];
    if (st <= 0.0f) continue;
    float keep = exp(-st * ds), p_in = p[ch];
    float scattered = p[ch] * (ss / st) * (1.0f - keep);
    if (scattered > 0.0f) splat(g, sigma_s, ch, mid, ch, scattered, deposit);
    total += fmax(scattered, 0.0f);
    p[ch] *= keep;
    if (g_phase == 0.0f) continue;
    float sr = (1.0f - g_phase) * ss, tr = st - g_phase * ss;
    float keep_r = exp(-tr * ds);
    float scattered_r = tr > 0.0f ? q[ch] * (sr / tr) * (1.0f - keep_r) : 0.0f;
    if (scattered_r > 0.0f) splat(g, sigma_s, ch, mid, ch, scattered_r, source);
    // What the scaled beam carries beyond the real one is light scattered forward; its
    // scattering here (sigma_s x its path in the piece) is a multiple-term emission.
    if (with_flow && tr > 0.0f) {
      float fwd = ss * (q[ch] * (1.0f - keep_r) / tr - p_in * (1.0f - keep) / st);
      if (fwd > 0.0f) splat(g, sigma_s, ch, mid, ch, fwd, extra);
    }
    q[ch] *= keep_r;
  }
  if (with_flow && total > 0.0f) {
    float d[3] = {dir.x, dir.y, dir.z};
    for (int k = 0; k < 3; ++k) splat(g, sigma_s, -1, mid, k, total * d[k], flow);
  }
  *power = (float3)(p[0], p[1], p[2]);
  *scaled = g_phase == 0.0f ? *power : (float3)(q[0], q[1], q[2]);
}

__kernel void march_rays(float3 origin, float voxel, int nx, int ny, int nz,
                         __global const float* sigma_s, __global const float* sigma_t,
                         __global const float* n_field, __global const float* grad_field,
                         __global const float* rays, int ray_count, int bend, float delta,
                         float cutoff, float g_phase, __global float* deposit,
                         __global float* source, __global float* flow, int with_flow) {
  int r = get_global_id(0);
  if (r >= ray_count) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  __global const float* ray = rays + RAY_FLOATS * r;
  float3 o = (float3)(ray[0], ray[1], ray[2]);
  float3 d = (float3)(ray[3], ray[4], ray[5]);
  float3 power = (float3)(ray[6], ray[7], ray[8]), scaled = power;
  float start = fmax(power.x, fmax(power.y, power.z)), stop = cutoff * start;
  float t0, t1;
  if (start <= 0.0f || !grid_interval(&g, o, d, &t0, &t1)) return;
  if (!bend) {
    Dda s;
    dda_init(&s, o, d, g.origin, g.voxel, (int3)(nx, ny, nz), t0, t1);
    float a, b;
    int3 c;
    while (dda_next(&s, &a, &b, &c) && fmax(scaled.x, fmax(scaled.y, scaled.z)) > stop)
      deposit_piece(&g, sigma_s, sigma_t, g_phase, c, o + d * (0.5f * (a + b)), d, b - a, &power,
                    &scaled, deposit, source, flow, with_flow);
    return;
  }
  float3 x = o + d * t0;
  float n;
  trilinear(&g, n_field, 1, x, &n);
  float3 v = n * d;
  int max_steps = (int)(4.0f * (nx + ny + nz) * voxel / delta) + 8;
  for (int i = 0; i < max_steps && fmax(scaled.x, fmax(scaled.y, scaled.z)) > stop; ++i) {
    float3 x0 = x;
    float ds = eikonal_step(&g, n_field, grad_field, delta, &x, &v);
    int3 c = voxel_of(&g, 0.5f * (x0 + x));
    if (!inside_grid(&g, c)) break;
    deposit_piece(&g, sigma_s, sigma_t, g_phase, c, 0.5f * (x0 + x), normalize(x - x0), ds, &power,
                  &scaled, deposit, source, flow, with_flow);
  }
}

// The positions of `steps` Eikonal steps from each ray's origin (no deposit): for checking the
// integrator against closed forms. out: 3 floats per step per ray.
__kernel void eikonal_trace(float3 origin, float voxel, int nx, int ny, int nz,
                            __global const float* n_field, __global const float* grad_field,
                            __global const float* rays, int ray_count, float delta, int steps,
                            __global float* out) {
  int r = get_global_id(0);
  if (r >= ray_count) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  __global const float* ray = rays + RAY_FLOATS * r;
  float3 x = (float3)(ray[0], ray[1], ray[2]);
  float n;
  trilinear(&g, n_field, 1, x, &n);
  float3 v = n * (float3)(ray[3], ray[4], ray[5]);
  for (int i = 0; i < steps; ++i) {
    eikonal_step(&g, n_field, grad_field, delta, &x, &v);
    __global float* o = out + 3 * ((size_t)r * steps + i);
    o[0] = x.x;
    o[1] = x.y;
    o[2] = x.z;
  }
}

// Marching in rounds, for interleaving with the diffusion (the paper's Table I): march_start
// moves each ray to where it enters the grid and stores its state (position, v, power, scaled
// power, stopping power, alive), then each march_round advances every live ray by at most `k`
// fixed steps (straight or bent; the voxel of a step's midpoint gives its coefficients), adds
// the deposits and counts the rays still alive.
#define STATE_FLOATS 16

__kernel void march_start(float3 origin, float voxel, int nx, int ny, int nz,
                          __global const float* n_field, __global const float* rays, int ray_count,
                          float cutoff, __global float* state) {
  int r = get_global_id(0);
  if (r >= ray_count) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  __global const float* ray = rays + RAY_FLOATS * r;
  __global float* s = state + STATE_FLOATS * r;
  float3 o = (float3)(ray[0], ray[1], ray[2]), d = (float3)(ray[3], ray[4], ray[5]);
  float start = fmax(ray[6], fmax(ray[7], ray[8]));
  float t0, t1;
  bool alive = start > 0.0f && grid_interval(&g, o, d, &t0, &t1);
  float3 x = o + d * (alive ? t0 : 0.0f);
  float n = 1.0f;
  if (alive) trilinear(&g, n_field, 1, x, &n);
  float v[15] = {x.x, x.y, x.z, n * d.x, n * d.y, n * d.z, ray[6], ray[7], ray[8],
                 ray[6], ray[7], ray[8], cutoff * start, alive ? 1.0f : 0.0f, 0.0f};
  for (int i = 0; i < 15; ++i) s[i] = v[i];
}

__kernel void march_round(float3 origin, float voxel, int nx, int ny, int nz,
                          __global const float* sigma_s, __global const float* sigma_t,
                          __global const float* n_field, __global const float* grad_field,
                          int ray_count, int bend, float delta, int k, float g_phase,
                          __global float* state, __global float* deposit, __global float* source,
                          __global float* flow, int with_flow, volatile __global int* alive_count) {
  int r = get_global_id(0);
  if (r >= ray_count) return;
  __global float* s = state + STATE_FLOATS * r;
  if (s[13] == 0.0f) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  float3 x = (float3)(s[0], s[1], s[2]), v = (float3)(s[3], s[4], s[5]);
  float3 power = (float3)(s[6], s[7], s[8]), scaled = (float3)(s[9], s[10], s[11]);
  float stop = s[12];
  bool alive = true;
  for (int i = 0; i < k && alive; ++i) {
    float3 x0 = x;
    float ds;
    if (bend) {
      ds = eikonal_step(&g, n_field, grad_field, delta, &x, &v);
    } else {
      x = x0 + delta * normalize(v);
      ds = delta;
    }
    int3 c = voxel_of(&g, 0.5f * (x0 + x));
    if (!inside_grid(&g, c)) {
      alive = false;
      break;
    }
    deposit_piece(&g, sigma_s, sigma_t, g_phase, c, 0.5f * (x0 + x), normalize(x - x0), ds, &power,
                  &scaled, deposit, source, flow, with_flow);
    alive = fmax(scaled.x, fmax(scaled.y, scaled.z)) > stop;
  }
  float out[13] = {x.x, x.y, x.z, v.x, v.y, v.z, power.x, power.y, power.z,
                   scaled.x, scaled.y, scaled.z, alive ? 1.0f : 0.0f};
  for (int i = 0; i < 12; ++i) s[i] = out[i];
  s[13] = out[12];
  if (alive) atomic_inc(alive_count);
}
