// The `single` pipeline's per-sample factor with exact transmittance (setting exact_tr 1), after
// kernels/common/: optical depths are summed through the voxels (DDA) instead of read
// from the samples' spherical harmonics. The factor is the same as shaders/single/shade.comp's:
//   weight * sigma_s * T(to eye) * sum over lights of E * T(to light) * HG
// T(to light) depends only on the light's position (or direction), so light_transmittance runs
// for a light when it appears or moves; shade_exact runs every frame and sums the eye's DDA only.
// Samples outside the surface (the shell) measure from `at`, their anchor inside.
//
// With `gradient` set, each sample's transmittance is modelled over its Gaussian as
// T(x) = T(a) exp(-g . (x - a)), g the gradient of the channel-mean optical depth (to the eye plus
// the lights' contribution-weighted mean) by slope-limited differences over the Gaussian's sigma
// s. A Gaussian times that exponential is the Gaussian moved by -g s^2 and scaled by
// exp(-g . (b - a) + |g|^2 s^2 / 2): the splat then integrates T along the view ray instead of
// taking it at the centre, which near a face (where single scattering is strongest) the centre
// value overestimates on one side and the clip at the surface cuts off the other. With `hessian`
// the model adds 1/2 sum_k c_k (x_k - a_k)^2 (second differences): the Gaussian is also
// stretched or narrowed per axis (shift[i], axes[i]; see shade_exact).

#define INVISIBLE_DEPTH 40.0f

// Optical depth of the channel mean from o towards d over [0, t1].
float mean_depth(const Grid* g, __global const float* sigma_t, __global const float* bound, float3 o, float3 d,
                 float t1) {
  float3 tau = optical_depth3_bounded(g, sigma_t, bound, o, d, 0.0f, t1);
  return (tau.x + tau.y + tau.z) / 3.0f;
}

// Inside a voxel with extinction, on its plane's inside (bound: boundary_planes.hpp; null: no
// planes, mesh_bound 0).
bool in_medium(const Grid* g, __global const float* sigma_t, __global const float* bound, float3 p) {
  int3 c = voxel_of(g, p);
  if (!(voxel_sigma(g, sigma_t, c, 0) + voxel_sigma(g, sigma_t, c, 1) + voxel_sigma(g, sigma_t, c, 2) > 0.0f))
    return false;
  if (bound == 0) return true;
  float4 plane = vload4(voxel_index(g, c.x, c.y, c.z), bound);
  float3 centre = g->origin + g->voxel * (convert_float3(c) + 0.5f);
  return dot(plane.xyz, p - centre) <= plane.w;
}

// Mean optical depth from p to the target: a point (directional 0) or along -dir to infinity.
float depth_to(const Grid* g, __global const float* sigma_t, __global const float* bound, float3 p, float3 target,
               int directional) {
  if (directional) return mean_depth(g, sigma_t, bound, p, target, INFINITY);
  float3 d = target - p;
  float len = length(d);
  return len > 0.0f ? mean_depth(g, sigma_t, bound, p, d / len, len) : 0.0f;
}

// Gradient of depth_to at a: per axis, differences over +-h to points inside the medium only
// (outside the optical depth does not continue the inside's), the smaller of the two slopes when
// both agree in sign and zero when they disagree (minmod: a shadow edge or a layer boundary
// does not make a steep slope out of one side). *curv: the second differences where both sides
// are inside (else zero). Where neither point at +-h is inside (a medium thinner than 2 h along
// the axis: a one-voxel slab under a Gaussian wider than a voxel) the step halves, up to four
// times: across such a slab the depth changes by its full optical thickness, and a zero slope
// kept the centre's transmittance over the whole Gaussian (6.7x the single term's bound at
// sigma_t x voxel 1000).
float3 depth_gradient(const Grid* g, __global const float* sigma_t, __global const float* bound, float3 a,
                      float tau0, float3 target,
                      int directional, float h, float4 plane, float3* curv) {
  float out[3], c2[3];
  for (int k = 0; k < 3; ++k) {
    float hk = h;
    float3 axis = (float3)(k == 0 ? 1.0f : 0.0f, k == 1 ? 1.0f : 0.0f, k == 2 ? 1.0f : 0.0f);
    bool ip = false, im = false;
    for (int tries = 0; tries < 5 && !ip && !im; ++tries) {
      if (tries > 0) hk *= 0.5f;
      float3 e = axis * hk;
      // A piece split at a jump (plane: its side is n . x <= d) differences on its side only.
      ip = in_medium(g, sigma_t, bound, a + e) && dot(plane.xyz, a + e) <= plane.w;
      im = in_medium(g, sigma_t, bound, a - e) && dot(plane.xyz, a - e) <= plane.w;
    }
    float3 e = axis * hk;
    float fwd = ip ? (depth_to(g, sigma_t, bound, a + e, target, directional) - tau0) / hk : 0.0f;
    float bwd = im ? (tau0 - depth_to(g, sigma_t, bound, a - e, target, directional)) / hk : 0.0f;
    float s = 0.0f;
    c2[k] = 0.0f;
    if (ip && im) {
      s = fwd * bwd > 0.0f ? (fabs(fwd) < fabs(bwd) ? fwd : bwd) : 0.0f;
      // Where the slopes disagree in sign (a thin feature, an edge of the grid's medium) the
      // parabola would be a wrong peak or trough: no curvature there.
      if (fwd * bwd > 0.0f) c2[k] = (fwd - bwd) / hk;
    } else if (ip) {
      s = fwd;
    } else if (im) {
      s = bwd;
    }
    out[k] = s;
  }
  *curv = (float3)(c2[0], c2[1], c2[2]);
  return (float3)(out[0], out[1], out[2]);
}

// out[3 i + c]: transmittance of channel c from sample i to light `light`; with `gradient`,
// grad[3 i ..]: the gradient of its channel-mean optical depth.
__kernel void light_transmittance(float3 origin, float voxel, int nx, int ny, int nz,
                                  __global const float* sigma_t, __global const float* bound, __global const float* at,
                                  __global const float* sigma, __global const float* planes, int count,
                                  __global const float* lights, int light,
                                  int gradient, __global float* out, __global float* grad) {
  int i = get_global_id(0);
  if (i >= count) return;
  Grid grid = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  float3 b = vload3(i, at);
  Light L = load_light(lights, light);
  float3 wl;
  float dist;
  light_irradiance(L, b, 0, &wl, &dist);  // the direction and distance of every channel
  float3 taus = optical_depth3_bounded(&grid, sigma_t, bound, b, wl, 0.0f, dist);
  float tau_ch[3] = {taus.x, taus.y, taus.z};
  float mean = 0.0f;
  for (int ch = 0; ch < 3; ++ch) {
    out[3 * i + ch] = exp(-tau_ch[ch]);
    mean += tau_ch[ch] / 3.0f;
  }
  if (!gradient) return;
  int directional = L.type == 1;
  float3 curv;
  float3 g = depth_gradient(&grid, sigma_t, bound, b, mean, directional ? -L.direction : L.position, directional, sigma[i],
                            vload4(i, planes), &curv);
  vstore3(g, 2 * i, grad);
  vstore3(curv, 2 * i + 1, grad);
}

// light_tr: light_count blocks of 3 * count floats from light_transmittance (light_grad alike,
// read with `gradient`). out[i]: the factor, w the log of the moved Gaussian's scale (tr_gradient;
// for tests, the splat integrates in the sample's own frame: axes[i].w); shift[i]: the
// offset of the Gaussian's centre; per_light[4 (i light_count + l) + c]: light l's share of the
// factor without its phase (the splat evaluates that per view ray); cut[3 i .. 3 i + 2]: the
// depth cuts, see below.
// The cut-off radius around a Gaussian's moved centre: 3 sigma (its widest axis, at least the
// sample's own s), widened by the move so that the ball around the sample's own centre, where the
// product is evaluated, stays covered. The splat covers this ball (shift's w).
float splat_reach(float3 axis, float s, float3 offset) {
  return 3.0f * fmax(fmax(axis.x, fmax(axis.y, axis.z)), s) + length(offset);
}

__kernel void shade_exact(float3 origin, float voxel, int nx, int ny, int nz, __global const float* sigma_t,
                          __global const float* bound,
                          __global const float* at, __global const float* position, __global const float* sigma,
                          __global const float* weight, __global const float* sigma_s, __global const float* planes,
                          int count,
                          __global const float* lights, int light_count, __global const float* light_tr,
                          __global const float* light_grad, int gradient, int hessian, float max_gs, float g_phase, float3 eye,
                          float sigma_scale, __global float4* out, __global float4* shift, __global float4* axes,
                          __global float4* cut, __global float* per_light) {
  int i = get_global_id(0);
  if (i >= count) return;
  Grid grid = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  float3 b = vload3(i, at);
  float3 to_eye = eye - b;
  float de = length(to_eye);
  float3 v = to_eye / de;
  float res[3];
  float view_mean = 0.0f;
  float3 light_g = (float3)(0.0f), light_c = (float3)(0.0f);
  float light_w = 0.0f;
  float tau_min = INFINITY;  // the least optical depth (eye plus a light) of any channel that adds
  float3 view_taus = optical_depth3_bounded(&grid, sigma_t, bound, b, v, 0.0f, de);
  float view_tau[3] = {view_taus.x, view_taus.y, view_taus.z};
  for (int ch = 0; ch < 3; ++ch) {
    float tau = view_tau[ch];
    view_mean += tau / 3.0f;
    float view = exp(-tau);
    float sum = 0.0f;
    for (int l = 0; l < light_count; ++l) {
      float3 wl;
      float dist;
      float e = light_irradiance(load_light(lights, l), b, ch, &wl, &dist);
      if (e <= 0.0f) {
        per_light[4 * ((size_t)i * light_count + l) + ch] = 0.0f;
        continue;
      }
      float tr = light_tr[((size_t)l * count + i) * 3 + ch];
      // Without the phase, which the splat takes per view ray.
      per_light[4 * ((size_t)i * light_count + l) + ch] = weight[i] * sigma_s[3 * i + ch] * view * e * tr;
      float c = e * tr * hg_phase(dot(wl, -v), g_phase);
      sum += c;
      if (c > 0.0f) tau_min = fmin(tau_min, tau - log(tr));
      if (gradient) {
        light_g += c * vload3(2 * ((size_t)l * count + i), light_grad);
        light_c += c * vload3(2 * ((size_t)l * count + i) + 1, light_grad);
        light_w += c;
      }
    }
    res[ch] = weight[i] * sigma_s[3 * i + ch] * view * sum;
  }
  // A sample whose light reaches the eye through more than INVISIBLE_DEPTH (exp(-40) = 4e-18 of
  // what it scatters) in every channel adds nothing: a zero factor, which the splat draws as a
  // degenerate quad, and no gradient (six DDAs; in a dense medium most samples lie that deep).
  bool visible = tau_min < INVISIBLE_DEPTH;
  if (!visible) res[0] = res[1] = res[2] = 0.0f;
  float3 offset = (float3)(0.0f);
  float log_scale = 0.0f;
  float depth_p = 0.0f;  // the model's optical depth at p less at the anchor: g . (p - a) + ...
  float4 depth_cut = (float4)(0.0f);  // zeros: no cut
  float4 quad_slope = (float4)(0.0f), quad_curv = (float4)(0.0f);  // zeros: no cut
  float s = sigma[i] * sigma_scale;  // sample_fraction widens the Gaussians of the prefix drawn
  float3 axis = (float3)(s);
  if (gradient && visible) {
    float3 curv;
    float3 g = depth_gradient(&grid, sigma_t, bound, b, view_mean, eye, 0, s, vload4(i, planes), &curv);
    if (light_w > 0.0f) {
      g += light_g / light_w;
      curv += light_c / light_w;
    }
    // An optional bound on |g| s (tr_gradient_max; the depth cut below already keeps a wrong slope
    // from brightening the Gaussian, and the splat integrates in the sample's own frame).
    float gs = length(g) * s;
    if (gs > max_gs) g *= max_gs / gs;
    if (!hessian) curv = (float3)(0.0f);
    // tau(x) ~ tau(a) + g.(x - a) + 1/2 sum_k curv_k (x_k - a_k)^2 around the sample's centre p:
    // slope g + curv (p - a), precision per axis 1/s^2 + curv (kept within [1/(2s)^2, (2/s)^2]).
    float3 p = vload3(i, position);
    float3 d = p - b;
    float inv = 1.0f / (s * s);
    float3 prec = clamp(inv + curv, 0.25f * inv, 4.0f * inv);
    curv = prec - inv;
    float3 gp = g + curv * d;
    offset = -gp / prec;
    // The moved Gaussian's scale's logarithm: in a dense medium it is |g|^2 s^2 / 2, far past
    // float's range, and the moved Gaussian's mass in the medium as small (for tests: the splat
    // integrates about p, with depth_p).
    depth_p = dot(g, d) + 0.5f * dot(curv * d, d);
    log_scale = -depth_p + 0.5f * dot(gp * gp, 1.0f / prec);
    axis = rsqrt(prec);
    // The linear model's optical depth, tau_min + g . (x - a), is negative beyond a plane, where
    // its transmittance would exceed one (a wrong slope, a layer it does not fit): the splat
    // integrates only on the plane's near side (n . x <= w, as a split piece's plane).
    if (isfinite(tau_min) && (g.x != 0.0f || g.y != 0.0f || g.z != 0.0f))
      depth_cut = (float4)(-g, tau_min - dot(g, b));
    // The model with its curvature, tau_min + g . (x - a) + 1/2 sum_k curv_k (x_k - a_k)^2, goes
    // negative on the near side of that plane too where the curvature is concave (it widens the
    // Gaussian, and its depth falls away from the centre): the splat integrates only where this
    // quadratic is >= 0, its zero set along each view ray. Kept about the sample's centre p (the
    // splat measures from it): depth tau_min + depth_p, slope gp there. Where no axis is concave
    // the quadratic lies above the linear model, and the linear cut alone is the same; where it
    // stays >= 0 over the ball the splat covers (within r of p: the ball's radius about the moved
    // centre, splat_reach, plus the move), it cuts nothing. Neither writes a second cut.
    float3 concave = fmin(curv, 0.0f);
    if (isfinite(tau_min) && (concave.x < 0.0f || concave.y < 0.0f || concave.z < 0.0f)) {
      float tau_p = tau_min + depth_p;
      float r = splat_reach(axis, s, offset) + length(offset);
      if (tau_p - length(gp) * r + 0.5f * (concave.x + concave.y + concave.z) * r * r < 0.0f) {
        quad_slope = (float4)(gp, tau_p);
        quad_curv = (float4)(curv, 0.0f);
      }
    }
  }
  cut[3 * i] = depth_cut;
  cut[3 * i + 1] = quad_slope;
  cut[3 * i + 2] = quad_curv;
  out[i] = (float4)(res[0], res[1], res[2], log_scale);
  shift[i] = (float4)(offset, splat_reach(axis, s, offset));
  // The Gaussian's standard deviation per axis; w: depth_p. The splat integrates the product in
  // the frame of the sample's own centre p, exp(-|x - p|^2_prec / 2 - gp . (x - p) - depth_p),
  // whose terms stay small where the moved Gaussian's (its distance from the eye's ray squared,
  // and log_scale) reach 1e6 in a dense medium and cancel to nothing in float.
  axes[i] = (float4)(axis, depth_p);
}
