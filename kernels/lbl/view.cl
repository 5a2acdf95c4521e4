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
// way to the eye. With lobes > 1 (several lights, pipelines/lbl/lbl_frame.hpp light_lobes) the
// deposit and flow hold each light's, one after the other (3 and 6 floats a voxel each), and each
// light's deposit takes its own lobe: one mean direction for lights from different sides would
// point between them and weight both lights by a lobe neither has. The multiple term's
// emission: the lattice's light isotropic (or g_flux, below); with second the second
// scattering's light, which the gather found travelling about its mean direction m (|m| <= 1,
// kernels/lbl/second.cl), by the same model: 4 pi HG(g |m|, m . w_out) (g_second = g; 0:
// isotropic). Next to a surface m points out of the medium, so the eye sees
// more of that light face on and less at grazing angles than an isotropic emission gives.
// scaled_view (g_scale = g): the multiple term, the lattice's delta-Eddington scaled light, is
// gathered as that scaled medium emits and attenuates it: (1 - g) x the irradiance (sigma_s'
// for sigma_s) through sigma_t' = sigma_t - g sigma_s.
// tms (with g > 0, the default; Nakajima and Tanaka's TMS correction): the eye sees the
// delta-Eddington scaled problem the march and the lattice solve, all of it through sigma_t'
// (the light the real phase's forward peak sends on towards the eye not counted as lost), with
// that problem's isotropic first scattering replaced by the real phase's: the lattice's and the
// second scattering's light emitted by sigma_s (1 - g), the scaled beam's (the real beam's and
// the forward-scattered light's) by sigma_s 4 pi HG. The single term stays the real medium's
// (through sigma_t); what the same light gains through sigma_t' is the multiple term's.

float single_phase(__global const float* deposit, __global const float* flow, float g, int v,
                   float3 to_eye) {
  float total = deposit[v] + deposit[v + 1] + deposit[v + 2];
  float3 m = (float3)(flow[v], flow[v + 1], flow[v + 2]);
  float len = length(m);
  if (!(total > 0.0f) || !(len > 1e-6f * total)) return 1.0f;
  float ge = g * fmin(len / total, 1.0f);
  return 4.0f * PI * hg_phase(dot(m, to_eye) / len, ge);
}

// One piece of length ds in voxel v: the emission `es` through the real sigma_t (transmittance
// tr), `em` times emit_scale through sigma_t - g_scale sigma_s (trm), less `sub` through the
// real sigma_t.
void gather_piece(__global const float* sigma_t, __global const float* sigma_s, float g_scale,
                  float emit_scale, float3 es, float3 em, float3 sub, int v, float ds,
                  float inv_4pi_v, float3* tr, float3* trm, float3* radiance) {
  float st[3] = {sigma_t[v], sigma_t[v + 1], sigma_t[v + 2]};
  float ss[3] = {sigma_s[v], sigma_s[v + 1], sigma_s[v + 2]};
  float e1[3] = {es.x, es.y, es.z}, e2[3] = {em.x, em.y, em.z}, e3[3] = {sub.x, sub.y, sub.z};
  float t[3] = {tr->x, tr->y, tr->z}, tm[3] = {trm->x, trm->y, trm->z};
  float L[3] = {0.0f, 0.0f, 0.0f};
  for (int ch = 0; ch < 3; ++ch) {
    float x = st[ch] * ds;
    float w = x > 1e-4f ? (1.0f - exp(-x)) / st[ch] : ds * (1.0f - 0.5f * x);
    float sm = st[ch] - g_scale * ss[ch], xm = sm * ds;
    float wm = xm > 1e-4f ? (1.0f - exp(-xm)) / sm : ds * (1.0f - 0.5f * xm);
    L[ch] = (t[ch] * (e1[ch] - e3[ch]) * w + tm[ch] * emit_scale * e2[ch] * wm) * inv_4pi_v;
    t[ch] *= exp(-x);
    tm[ch] *= exp(-xm);
  }
  *radiance += (float3)(L[0], L[1], L[2]);
  *tr = (float3)(t[0], t[1], t[2]);
  *trm = (float3)(tm[0], tm[1], tm[2]);
}

// The lattice's emission and the second scattering's (in the real sigma_s's share). The
// lattice's light is isotropic unless g_flux != 0: with its direction m = J / phi per voxel
// (lattice_flux), a radiance (phi + 3 J . w) / (4 pi) scattered by a phase of first moment g
// emits (phi + 3 g J . w_out) / (4 pi), so the emission is scaled by 1 + 3 g m . w_out (not
// below 0). With second (second_scale = 1 / (1 - g), else 0) the second scattering's light
// Q2 / (1 - g) is added, by the phase about the gather's direction (g_second != 0) or else with
// the lattice's.
float3 diffuse_emission(__global const float* irr, __global const float* lflux, float g_flux,
                        __global const float* second, __global const float* second_dir,
                        float second_scale, float g_second, int v, float3 to_eye) {
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
  return e + q;
}

typedef struct {
  __global const float* deposit;
  __global const float* flow;  // with_flow: the light's direction, then the forward-scattered
  __global const float* irr;
  __global const float* lflux;
  __global const float* second;
  __global const float* second_dir;
  __global const float* sigma_t;
  __global const float* sigma_s;
  float w_single, w_multiple, g, g_flux, second_scale, g_second, g_scale;
  int with_flow, lobes, tms, voxels;
} ViewInputs;

// One piece of the eye ray (length ds in voxel v, travelling to_eye towards the eye). The
// multiple term: the lattice's and the second scattering's light, plus (with_flow) the light
// the delta-Eddington beam kept forward (`extra`), scattered with the phase about the light's
// direction; with tms as the header says.
void view_piece(const ViewInputs* in, int v, float3 to_eye, float ds, float inv_4pi_v,
                float3* tr, float3* trm, float3* radiance) {
  float3 single = (float3)(0.0f), beam = (float3)(0.0f);
  for (int l = 0; l < in->lobes; ++l) {
    __global const float* dep = in->deposit + 3 * l * in->voxels;
    __global const float* fl = in->flow + 6 * l * in->voxels;
    float phase = in->with_flow ? single_phase(dep, fl, in->g, v, to_eye) : 1.0f;
    single += phase * (float3)(dep[v], dep[v + 1], dep[v + 2]);
    if (in->with_flow) {
      __global const float* extra = fl + 3 * in->voxels;
      beam += phase * (float3)(extra[v], extra[v + 1], extra[v + 2]);
    }
  }
  float3 diffuse = (float3)(0.0f);
  if (in->w_multiple != 0.0f)
    diffuse = diffuse_emission(in->irr, in->lflux, in->g_flux, in->second, in->second_dir,
                               in->second_scale, in->g_second, v, to_eye);
  float3 es = in->w_single * single;
  if (in->tms)
    gather_piece(in->sigma_t, in->sigma_s, in->g, 1.0f, es,
                 in->w_multiple * ((1.0f - in->g) * diffuse + beam + single),
                 in->w_multiple * single, v, ds, inv_4pi_v, tr, trm, radiance);
  else
    gather_piece(in->sigma_t, in->sigma_s, in->g_scale, 1.0f - in->g_scale, es,
                 in->w_multiple * (diffuse + beam), (float3)(0.0f), v, ds, inv_4pi_v, tr, trm,
                 radiance);
}

__kernel void view_pass(float3 origin, float voxel, int nx, int ny, int nz,
                        __global const float* sigma_t, __global const float* n_field,
                        __global const float* grad_field, __global const float* deposit,
                        __global const float* irr, float w_single, float w_multiple,
                        __global const float* flow, float g_phase, int with_flow, int lobes,
                        __global const float* sigma_s, float g_scale, __global const float* lflux,
                        float g_flux, __global const float* second,
                        __global const float* second_dir, float second_scale, float g_second,
                        int tms, __global const float* camera, int width, int height, int bend,
                        float delta, __global float* out) {
  int px = get_global_id(0), py = get_global_id(1);
  if (px >= width || py >= height) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  Cam cam = load_camera(camera);
  float3 d = camera_ray(cam, px, py, width, height, 0.5f, 0.5f);
  float inv_4pi_v = INV_4PI / (voxel * voxel * voxel);
  float3 tr = (float3)(1.0f), trm = (float3)(1.0f), radiance = (float3)(0.0f);
  ViewInputs in = {deposit,  flow,       irr,        lflux,        second,
                   second_dir, sigma_t,  sigma_s,    w_single,     w_multiple,
                   g_phase,  g_flux,     second_scale, g_second,   g_scale,
                   with_flow, lobes, tms, nx * ny * nz};
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
        view_piece(&in, v, -d, b - a, inv_4pi_v, &tr, &trm, &radiance);
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
        view_piece(&in, k, normalize(x0 - x), ds, inv_4pi_v, &tr, &trm, &radiance);
      }
    }
  }
  size_t i = 3 * ((size_t)py * width + px);
  out[i] = radiance.x;
  out[i + 1] = radiance.y;
  out[i + 2] = radiance.z;
}
