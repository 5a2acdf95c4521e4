// The `psf` pipeline's view pass (Algorithm 2), one light per launch, added into `out`:
// the view ray crosses the voxels exactly (DDA) in sub-steps of at most `step` voxels, each
// weighted by the exact integral of the view transmittance over it (as the reference marcher).
// At each sub-step's midpoint p, with the light volume of pipelines/psf/light_pyramid.hpp:
//   single:   sigma_s * L0(p) * HG(theta)
//   multiple: Lookup(p, w) * P_MS(l, theta) * exp(-alpha theta^2 / l) * A
// where l = l1 + l2 and S = s1 + s2 add the view part (accumulated here) and the light part (from
// the volume), w is the blur width of equation 18 and Lookup is the pyramid (blurred b * L0) at
// that width, interpolated between levels. The lookup is refreshed only once the ray has passed
// the blur sphere's projection along the light direction (figure 9), and so is the weight
// P_MS exp(-alpha theta^2 / l) A (measured: sphere's error unchanged to 5 digits); between
// refreshes both are held while the measure (view transmittance or absorption) is integrated
// per sub-step. A (`atten`): 0 the paper's exp(-tau2) on top of the
// light volume's own attenuation (the light segment counted twice), 1 nothing more (the view
// transmittance only), 2 absorption only along the view segment instead of extinction.
// That is `model` 0 (the paper's). `model` 1 (`orders`, pipelines/psf/orders.hpp) reads instead
// the orders' bands on their coarse grid at every sub-step:
//   multiple: b * (phi_1 HG(g^2) + phi_2 HG(g^3) + phi_rest HG(g_rest)),  g_rest = G / phi_rest
// (with `conserve`, b_eff = b (1 - exp(-c dl)) / (c dl), dl = `sat`, as the orders collide)
// weighted by the view transmittance like the single term, plus (`flux`) the P1 part of the
// diffusive flux J = -D grad(phi) scattered towards the camera: 3 g D / (4 pi) dphi/dt along the
// view ray (clamped at zero).

typedef struct {
  __global const float4* data;
  __global const int4* levels;  // (offset, nx, ny, nz) per level
  __global const float* widths; // total blur width per level, world units
  int count;
  float3 origin;
  float voxel;  // level 0's voxel
} Pyramid;

// The 8 voxels around p on a grid of `cell` whose corner is `origin` (clamped to the grid) and
// their trilinear weights.
void trilinear_corners(int nx, int ny, int nz, float3 origin, float cell, float3 p, int* index,
                       float* weight) {
  float3 q = (p - origin) / cell - 0.5f;
  float3 f = q - floor(q);
  int3 c0 = convert_int3(floor(q));
  for (int j = 0; j < 8; ++j) {
    int dx = j & 1, dy = (j >> 1) & 1, dz = j >> 2;
    int x = clamp(c0.x + dx, 0, nx - 1), y = clamp(c0.y + dy, 0, ny - 1),
        z = clamp(c0.z + dz, 0, nz - 1);
    index[j] = (z * ny + y) * nx + x;
    weight[j] = (dx ? f.x : 1.0f - f.x) * (dy ? f.y : 1.0f - f.y) * (dz ? f.z : 1.0f - f.z);
  }
}

float4 trilinear(__global const float4* data, int offset, int nx, int ny, int nz, float3 origin,
                 float cell, float3 p) {
  int index[8];
  float weight[8];
  trilinear_corners(nx, ny, nz, origin, cell, p, index, weight);
  float4 sum = (float4)(0.0f);
  for (int j = 0; j < 8; ++j) sum += weight[j] * data[offset + index[j]];
  return sum;
}

float4 level_at(const Pyramid* P, int k, float3 p) {
  int4 L = P->levels[k];
  return trilinear(P->data, L.x, L.y, L.z, L.w, P->origin, P->voxel * (float)(1 << k), p);
}

// The blurred source at p for the widths w (per channel), each linear between the two levels
// around its width; a level is read once however many channels need it.
float3 lookup3(const Pyramid* P, float3 p, float3 w) {
  int k[3];
  float f[3];
  for (int c = 0; c < 3; ++c) {
    float wc = channel_of(w, c);
    int kc = 0;
    while (kc + 1 < P->count && P->widths[kc + 1] <= wc) ++kc;
    k[c] = kc;
    f[c] = kc + 1 < P->count ? (wc - P->widths[kc]) / (P->widths[kc + 1] - P->widths[kc]) : 0.0f;
  }
  int lo = min(k[0], min(k[1], k[2])), hi = min(max(k[0], max(k[1], k[2])) + 1, P->count - 1);
  float4 levels[4];  // lo .. hi, at most 4 apart in practice; beyond, read directly
  for (int j = 0; j <= min(hi - lo, 3); ++j) levels[j] = level_at(P, lo + j, p);
  float out[3];
  for (int c = 0; c < 3; ++c) {
    int a = k[c] - lo, b = min(k[c] + 1, P->count - 1) - lo;
    float4 va = a <= 3 ? levels[a] : level_at(P, k[c], p);
    float4 vb = b <= 3 ? levels[b] : level_at(P, lo + b, p);
    out[c] = channel_of(va.xyz, c) + f[c] * (channel_of(vb.xyz, c) - channel_of(va.xyz, c));
  }
  return (float3)(out[0], out[1], out[2]);
}

// The orders' multiply scattered radiance factor at p (before b): each band with its phase.
float3 orders_at(__global const float4* bands, int nx, int ny, int nz, float3 origin, float cell,
                 float3 p, float cos_theta, float g, float3* fluence) {
  int index[8];
  float weight[8];
  trilinear_corners(nx, ny, nz, origin, cell, p, index, weight);
  float4 b[4] = {(float4)(0.0f), (float4)(0.0f), (float4)(0.0f), (float4)(0.0f)};
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 4; ++j) b[j] += weight[i] * bands[4 * index[i] + j];
  *fluence = b[0].xyz + b[1].xyz + b[2].xyz;
  float out[3];
  for (int c = 0; c < 3; ++c) {
    float rest = channel_of(b[2].xyz, c);
    float g_rest = rest > 0.0f ? clamp(channel_of(b[3].xyz, c) / rest, -0.99f, 0.99f) : 0.0f;
    out[c] = channel_of(b[0].xyz, c) * hg_phase(cos_theta, g * g) +
             channel_of(b[1].xyz, c) * hg_phase(cos_theta, g * g * g) +
             rest * hg_phase(cos_theta, g_rest);
  }
  return (float3)(out[0], out[1], out[2]);
}

// 1 / N(l) from the host's table, linear in ln(l).
float pms_inv_norm(__global const float* table, int n, float log_min, float log_max, float ell) {
  float x = (log(fmax(ell, 1e-30f)) - log_min) / (log_max - log_min) * (n - 1);
  x = clamp(x, 0.0f, (float)(n - 1));
  int i = min((int)x, n - 2);
  float f = x - i;
  return table[i] * (1.0f - f) + table[i + 1] * f;
}

float pms_stretch(float ell) { return ell < 1e-4f ? 1.0f : sqrt(ell / -expm1(-ell)); }

// Equation 18 with the 8/b shift (psf_model.hpp: blur_width2).
float blur_width2(float theta2, float ell, float S, float a_over_b, float shift) {
  if (ell <= shift || S <= 0.0f) return 0.0f;
  float l = ell - shift;
  float s = S * l / ell;
  return theta2 * l * s * s / (24.0f * (1.0f + theta2 * a_over_b * l * l / 12.0f));
}

__kernel void psf_march(float3 origin, float voxel, int nx, int ny, int nz,
                        __global const float* sigma_s, __global const float* sigma_t,
                        __global const float* lights, int light, float g_phase,
                        __global const float* camera, int width, int height, float step, int terms,
                        __global const float4* l0, __global const float4* path,
                        __global const float4* tau, __global const float4* pyramid,
                        __global const int4* levels, __global const float* widths, int level_count,
                        __global const float* pms, int pms_n, float pms_log_min, float pms_log_max,
                        float theta2, float alpha, float shift, int atten, float spacing,
                        int model, __global const float4* bands, int onx, int ony, int onz,
                        float ocell, float4 flux, float sat, __global float* out) {
  int px = get_global_id(0), py = get_global_id(1);
  if (px >= width || py >= height) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  Pyramid P = {pyramid, levels, widths, level_count, origin, voxel};
  Cam cam = load_camera(camera);
  float3 o = cam.position, d = camera_ray(cam, px, py, width, height, 0.5f, 0.5f);
  Light L = load_light(lights, light);
  float3 single = (float3)(0.0f), multiple = (float3)(0.0f);
  float t0, t1;
  if (grid_interval(&g, o, d, &t0, &t1)) {
    Dda s;
    dda_init(&s, o, d, origin, voxel, (int3)(nx, ny, nz), t0, t1);
    float3 tr = (float3)(1.0f), ell1 = (float3)(0.0f), tau1 = (float3)(0.0f);
    float s1 = 0.0f, next_lookup = -INFINITY, a, b, prev_t = -1.0f;
    float3 prev_phi = (float3)(0.0f);
    float3 blurred = (float3)(0.0f), weight = (float3)(0.0f);
    int3 c;
    while (dda_next(&s, &a, &b, &c) && fmax(tr.x, fmax(tr.y, tr.z)) > 1e-7f) {
      int u = 3 * voxel_index(&g, c.x, c.y, c.z);
      float3 st = vload3(0, sigma_t + u), ss = vload3(0, sigma_s + u);
      if (st.x <= 0.0f && st.y <= 0.0f && st.z <= 0.0f) continue;
      int n = max(1, (int)ceil((b - a) / (step * voxel)));
      float h = (b - a) / n;
      float3 seg_tr = exp(-st * h);
      float3 wint = select((1.0f - seg_tr) / st, h * (1.0f - 0.5f * st * h), isless(st * h, 1e-4f));
      for (int q = 0; q < n; ++q) {
        float tm = a + (q + 0.5f) * h;
        float3 p = o + d * tm;
        float3 wl;
        float dist;
        light_irradiance(L, p, 0, &wl, &dist);
        float cos_theta = clamp(dot(wl, d), -1.0f, 1.0f);
        if (terms & 1) {
          float3 lin = trilinear(l0, 0, nx, ny, nz, origin, voxel, p).xyz;
          single += tr * wint * ss * lin * hg_phase(cos_theta, g_phase);
        }
        if ((terms & 2) && model == 1) {
          float3 phi;
          float3 ms = orders_at(bands, onx, ony, onz, origin, ocell, p, cos_theta, g_phase, &phi);
          if (flux.x != 0.0f || flux.y != 0.0f || flux.z != 0.0f) {
            // The diffusive flux -D grad(phi) scattered towards the camera (its P1 part, g):
            // the fluence's derivative along the ray from the previous sample (or a half cell
            // ahead at the first).
            float3 deriv;
            if (prev_t < 0.0f) {
              float3 ahead;
              orders_at(bands, onx, ony, onz, origin, ocell, p + 0.5f * ocell * d, cos_theta,
                        g_phase, &ahead);
              deriv = (ahead - phi) / (0.5f * ocell);
            } else {
              deriv = (phi - prev_phi) / fmax(tm - prev_t, 1e-6f);
            }
            prev_phi = phi;
            prev_t = tm;
            ms = fmax(ms + flux.xyz * deriv, 0.0f);
          }
          // `conserve`: the orders' collisions saturate over a cell `sat` (orders.cl:
          // coarse_collision), and so does the scattering that sends them towards the camera.
          float3 se = ss;
          if (sat > 0.0f) {
            float3 u = st * sat;
            se = select(ss * (1.0f - exp(-u)) / u, ss * (1.0f - 0.5f * u), isless(u, 1e-4f));
          }
          multiple += tr * wint * se * ms;
        } else if (terms & 2) {
          if (tm >= next_lookup) {
            // The weight and the lookup, at the spacing of figure 9; held in between.
            float4 pl = trilinear(path, 0, nx, ny, nz, origin, voxel, p);
            float3 tau2 = trilinear(tau, 0, nx, ny, nz, origin, voxel, p).xyz;
            float3 ell = ell1 + 0.5f * ss * h + pl.xyz;
            float3 taut = tau1 + 0.5f * st * h + tau2;
            float S = s1 + 0.5f * h + pl.w;
            float theta = acos(cos_theta);
            float res[3], w[3];
            for (int ch = 0; ch < 3; ++ch) {
              float l = channel_of(ell, ch);
              float a_over_b = l > 0.0f ? fmax(channel_of(taut, ch) - l, 0.0f) / l : 0.0f;
              w[ch] = sqrt(blur_width2(theta2, l, S, a_over_b, shift));
              float k = pms_stretch(l);
              float pm = hg_phase(cos(theta / k), g_phase) * pms_inv_norm(pms, pms_n, pms_log_min, pms_log_max, l);
              float curv = l > 0.0f ? exp(-alpha * theta * theta / l) : 0.0f;
              res[ch] = pm * curv;
            }
            blurred = lookup3(&P, p, (float3)(w[0], w[1], w[2]));
            weight = (float3)(res[0], res[1], res[2]);
            if (atten == 0) weight *= exp(-tau2);
            float sin_phi = sqrt(fmax(1.0f - cos_theta * cos_theta, 0.0f));
            float wmin = fmin(w[0], fmin(w[1], w[2]));
            next_lookup = tm + spacing * wmin / fmax(sin_phi, 0.1f);
          }
          float3 measure = tr * wint;
          if (atten == 2) measure = exp(-(tau1 + 0.5f * st * h - (ell1 + 0.5f * ss * h))) * h;
          multiple += measure * blurred * weight;
        }
        tr *= seg_tr;
        ell1 += ss * h;
        tau1 += st * h;
        s1 += h;
      }
    }
  }
  int o3 = 3 * (py * width + px);
  float3 sum = ((terms & 1) ? single : (float3)(0.0f)) + ((terms & 2) ? multiple : (float3)(0.0f));
  out[o3] += sum.x;
  out[o3 + 1] += sum.y;
  out[o3 + 2] += sum.z;
}
