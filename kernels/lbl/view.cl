// View pass: per pixel, the eye ray gathers the light scattered in the voxels it crosses. A voxel
// scattering power S (watts, RGB) emits S / (4 pi V) per unit volume and solid angle (isotropic);
// S = w_single x deposit + w_multiple x irradiance selects the terms. Over a piece of length ds
// with transmittance tr so far, the radiance gained is tr S / (4 pi V) (1 - exp(-sigma_t ds)) /
// sigma_t. Straight rays cross the voxels exactly (DDA); with a varying n the ray follows the
// ray equation in fixed steps (refraction through the smoothed index).
// The single term's phase (with_flow, g != 0): the voxel's light arrives about the mean direction
// m = flow / (deposit summed over channels), |m| <= 1 (1 for one straight light); its
// distribution taken as HG(|m|) about m, and HG(g) * HG(|m|) = HG(g |m|) (their Legendre
// coefficients multiply), so the deposit is weighted by 4 pi HG(g |m|, m . w_out) with w_out the
// way to the eye. The multiple term's emission: the lattice's light isotropic (or g_flux, below);
// with second the second scattering's light, which the gather found travelling about its mean
// direction m (|m| <= 1, kernels/lbl/second.cl), by the same model: 4 pi HG(g |m|, m . w_out)
// (g_second = g; 0: isotropic). Next to a surface m points out of the medium, so the eye sees
// more of that light face on and less at grazing angles than an isotropic emission gives.
// scaled_view (g_scale = g): the multiple term, the lattice's delta-Eddington scaled light, is
// gathered as that scaled medium emits and attenuates it: (1 - g) x the irradiance (sigma_s'
// for sigma_s) through sigma_t' = sigma_t - g sigma_s.

float single_phase(__global const float* deposit, __global const float* flow, float g, int v,
                   float3 to_eye) {
  float total = deposit[v] + deposit[v + 1] + deposit[v + 2];
  float3 m = (float3)(flow[v], flow[v + 1], flow[v + 2]);
  float len = length(m);
  if (!(total > 0.0f) || !(len > 1e-6f * total)) return 1.0f;
  float ge = g * fmin(len / total, 1.0f);
  return 4.0f * PI * hg_phase(dot(m, to_eye) / len, ge);
}

float3 single_emission(__global const float* deposit, __global const float* flow, float w_single,
                       float g, int with_flow, int v, float3 to_eye) {
  float ws = w_single;
  if (with_flow && w_single != 0.0f) ws *= single_phase(deposit, flow, g, v, to_eye);
  return ws * (float3)(deposit[v], deposit[v + 1], deposit[v + 2]);
}

// One piece of length ds in voxel v: the single term's emission `es` through the real sigma_t
// (transmittance tr), the multiple term's `em` through sigma_t - g_scale sigma_s (trm) and
// times (1 - g_scale): with g_scale = g the lattice's similarity-scaled light is seen through
// the scaled medium too, its forward scattering not counted as loss.
void gather_piece(__global const float* sigma_t, __global const float* sigma_s, float g_scale,
                  float3 es, float3 em, int v, float ds, float inv_4pi_v, float3* tr, float3* trm,
                  float3* radiance) {
  float st[3] = {sigma_t[v], sigma_t[v + 1], sigma_t[v + 2]};
  float ss[3] = {sigma_s[v], sigma_s[v + 1], sigma_s[v + 2]};
  float e1[3] = {es.x, es.y, es.z}, e2[3] = {em.x, em.y, em.z};
  float t[3] = {tr->x, tr->y, tr->z}, tm[3] = {trm->x, trm->y, trm->z};
  float L[3] = {0.0f, 0.0f, 0.0f};
  for (int ch = 0; ch < 3; ++ch) {
    float x = st[ch] * ds;
    float w = x > 1e-4f ? (1.0f - exp(-x)) / st[ch] : ds * (1.0f - 0.5f * x);
    float sm = st[ch] - g_scale * ss[ch], xm = sm * ds;
    float wm = xm > 1e-4f ? (1.0f - exp(-xm)) / sm : ds * (1.0f - 0.5f * xm);
    L[ch] = (t[ch] * e1[ch] * w + tm[ch] * (1.0f - g_scale) * e2[ch] * wm) * inv_4pi_v;
    t[ch] *= exp(-x);
    tm[ch] *= exp(-xm);
  }
  *radiance += (float3)(L[0], L[1], L[2]);
  *tr = (float3)(t[0], t[1], t[2]);
  *trm = (float3)(tm[0], tm[1], tm[2]);
}

// The multiple term's emission: the lattice's, plus (with_flow) the light the delta-Eddington
// beam kept forward, scattered with the phase about the light's direction. The lattice's light
// is isotropic unless g_flux != 0: with its direction m = J / phi per voxel (lattice_flux), a
// radiance (phi + 3 J . w) / (4 pi) scattered by a phase of first moment g emits
// (phi + 3 g J . w_out) / (4 pi), so the emission is scaled by 1 + 3 g m . w_out (not below 0).
// With second (second_scale = 1 / (1 - g), else 0) the second scattering's light Q2 / (1 - g)
// is added, by the phase about the gather's direction (g_second != 0) or else with the lattice's.
float3 multiple_emission(__global const float* deposit, __global const float* irr,
                         __global const float* flow, float w_multiple, float g, int with_flow,
                         __global const float* lflux, float g_flux, __global const float* second,
                         __global const float* second_dir, float second_scale, float g_second,
                         int voxels, int v, float3 to_eye) {
  float3 e = (float3)(irr[v], irr[v + 1], irr[v + 2]);
  float3 q = second_scale * (float3)(second[v], second[v + 1], second[v + 2]);
  if (g_second != 0.0f) {
    float3 m = vload3(v / 3, second_dir);
    float len = length(m);
    if (len > 1e-6f) q *= 4.0f * PI * hg_phase(dot(m, to_eye) / len, g_second * fmin(len, 1.0f));
  }
  if (g_flux != 0.0f) {  // (the second scattering's light too when it has no phase of its own)
    float f = fmax(0.0f, 1.0f + 3.0f * g_flux * dot(vload3(v / 3, lflux), to_eye));
    e *= f;
    if (g_second == 0.0f) q *= f;
  }
  e += q;
  if (with_flow && w_multiple != 0.0f) {
    __global const float* extra = flow + 3 * voxels;
    e += single_phase(deposit, flow, g, v, to_eye) * (float3)(extra[v], extra[v + 1], extra[v + 2]);
  }
  return w_multiple * e;
}

__kernel void view_pass(float3 origin, float voxel, int nx, int ny, int nz,
                        __global const float* sigma_t, __global const float* n_field,
                        __global const float* grad_field, __global const float* deposit,
                        __global const float* irr, float w_single, float w_multiple,
                        __global const float* flow, float g_phase, int with_flow,
                        __global const float* sigma_s, float g_scale, __global const float* lflux,
                        float g_flux, __global const float* second,
                        __global const float* second_dir, float second_scale, float g_second,
                        __global const float* camera, int width, int height, int bend,
                        float delta, __global float* out) {
  int px = get_global_id(0), py = get_global_id(1);
  if (px >= width || py >= height) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  Cam cam = load_camera(camera);
  float3 d = camera_ray(cam, px, py, width, height, 0.5f, 0.5f);
  float inv_4pi_v = INV_4PI / (voxel * voxel * voxel);
  float3 tr = (float3)(1.0f), trm = (float3)(1.0f), radiance = (float3)(0.0f);
  float t0, t1;
  if (grid_interval(&g, cam.position, d, &t0, &t1)) {
    if (!bend) {
      Dda s;
      dda_init(&s, cam.position, d, g.origin, g.voxel, (int3)(nx, ny, nz), t0, t1);
      float a, b;
      int3 c;
      while (dda_next(&s, &a, &b, &c) && fmax(fmax(tr.x, fmax(tr.y, tr.z)),
                                               fmax(trm.x, fmax(trm.y, trm.z))) > 1e-6f) {
        int v = 3 * voxel_index(&g, c.x, c.y, c.z);
        gather_piece(sigma_t, sigma_s, g_scale,
                     single_emission(deposit, flow, w_single, g_phase, with_flow, v, -d),
                     multiple_emission(deposit, irr, flow, w_multiple, g_phase, with_flow, lflux,
                                       g_flux, second, second_dir, second_scale, g_second,
                                       nx * ny * nz, v, -d),
                     v, b - a, inv_4pi_v, &tr, &trm, &radiance);
      }
    } else {
      float3 x = cam.position + d * t0;
      float n;
      trilinear(&g, n_field, 1, x, &n);
      float3 v = n * d;
      int max_steps = (int)(4.0f * (nx + ny + nz) * voxel / delta) + 8;
      for (int i = 0; i < max_steps && fmax(fmax(tr.x, fmax(tr.y, tr.z)),
                                            fmax(trm.x, fmax(trm.y, trm.z))) > 1e-6f;
           ++i) {
        float3 x0 = x;
        float ds = eikonal_step(&g, n_field, grad_field, delta, &x, &v);
        int3 c = voxel_of(&g, 0.5f * (x0 + x));
        if (!inside_grid(&g, c)) break;
        int k = 3 * voxel_index(&g, c.x, c.y, c.z);
        float3 e = single_emission(deposit, flow, w_single, g_phase, with_flow, k,
                                   normalize(x0 - x));
        float3 em = multiple_emission(deposit, irr, flow, w_multiple, g_phase, with_flow, lflux,
                                      g_flux, second, second_dir, second_scale, g_second,
                                      nx * ny * nz, k, normalize(x0 - x));
        gather_piece(sigma_t, sigma_s, g_scale, e, em, k, ds, inv_4pi_v, &tr, &trm, &radiance);
      }
    }
  }
  size_t i = 3 * ((size_t)py * width + px);
  out[i] = radiance.x;
  out[i + 1] = radiance.y;
  out[i + 2] = radiance.z;
}
