// Deterministic single-scatter ray marcher: per pixel, the view ray crosses the voxels exactly
// (DDA); inside each voxel the in-scattering integral is summed over sub-steps of at most `step`
// voxels, each the exact integral of the view and light transmittances over the sub-step for a
// light optical depth linear across it (march_segment); the light's optical depth is exact
// through the voxels at the sub-steps' ends. Converges as step -> 0.
//
// The medium is the density grid inside the mesh (boundary.cl): the view ray is marched only over
// its segments inside, up to each crossing, and the light's optical depth sums the parts of the
// shadow ray inside. With a dielectric boundary (ior != 1) the view ray is split at every surface
// crossing into its reflected and refracted parts, weighted by Fresnel (a small stack, until the
// weight is negligible); light reaches a point inside along a straight shadow ray weighted by the
// Fresnel transmittance of the crossings.

// Light reaching p from light l, scattered into -d, before the medium's attenuation (*tau: the
// optical depth towards the light).
float unattenuated(const Grid* g, __global const float* sigma_t, __global const float* lights,
                   int l, float g_phase, int ch, float3 p, float3 d, Bvh bvh, float ior,
                   bool use_mesh, float* tau) {
  float3 wl;
  float dist;
  float e = light_irradiance(load_light(lights, l), p, ch, &wl, &dist);
  *tau = 0.0f;
  if (e <= 0.0f) return 0.0f;
  float fresnel_tr = 1.0f;
  *tau = use_mesh ? shadow_depth(g, sigma_t, ch, bvh, ior, p, wl, dist, &fresnel_tr)
                  : optical_depth(g, sigma_t, ch, p, wl, 0.0f, dist);
  return e * fresnel_tr * hg_phase(dot(wl, d), g_phase);
}

// The mean of exp(-f) over an interval on which f rises linearly from a to b:
// (exp(-a) - exp(-b)) / (b - a), for either order and without overflow.
float exp_mean(float a, float b) {
  float x = fabs(b - a);
  return exp(-fmin(a, b)) * (x > 1e-4f ? -expm1(-x) / x : 1.0f - 0.5f * x);
}

#define MAX_MARCH_LIGHTS 16
// The sub-steps' ends on the voxel's faces are taken this fraction of a sub-step inside it: a
// point on a face may round into the neighbour (the empty margin, for the medium's own faces),
// whose light path misses the medium.
#define FACE_INSET 1e-3f

// Single-scattered radiance along o + t d, t in [t0, t1], for one channel; *tr_end receives the
// view transmittance from t0 to t1. Over each sub-step [0, h] the optical depth to the eye grows
// as st u and the one to each light is taken linear between its values at the sub-step's ends,
// so the sub-step's integral of exp(-both) is exact for a linear light depth (a voxel's face):
// a midpoint value of the light's transmittance is off by its curvature over st h, which in a
// dense voxel (st h of 250) leaves 40% of the light out.
float march_segment(const Grid* g, __global const float* sigma_s, __global const float* sigma_t,
                    __global const float* lights, int light_count, float g_phase, int ch,
                    float3 o, float3 d, float t0, float t1, float step, Bvh bvh, float ior,
                    bool use_mesh, float* tr_end) {
  float a0, a1;
  *tr_end = 1.0f;
  if (!grid_interval(g, o, d, &a0, &a1)) return 0.0f;
  a0 = fmax(a0, t0);
  a1 = fmin(a1, t1);
  if (a1 <= a0) return 0.0f;
  light_count = min(light_count, MAX_MARCH_LIGHTS);
  Dda s;
  dda_init(&s, o, d, g->origin, g->voxel, (int3)(g->nx, g->ny, g->nz), a0, a1);
  float tr = 1.0f, radiance = 0.0f, a, b;
  float e0[MAX_MARCH_LIGHTS], tau0[MAX_MARCH_LIGHTS];
  // What the rest of the ray may still add, at most tr times the light reaching this voxel
  // unattenuated (albedo and the light's transmittance at most 1): the march stops once that is
  // under 1e-6 of what it has, or the view transmittance is under 1e-7 with no light here. A
  // cut-off on tr alone lost the light of a ray that runs towards a light through the medium
  // (its light transmittance rises as the view's falls: 0.31 of the value seen from inside a
  // dense box, docs/STRESS.md).
  float reach = INFINITY;
  int3 c;
  while (dda_next(&s, &a, &b, &c) && tr > 0.0f && (tr > 1e-7f || tr * reach > 1e-6f * radiance)) {
    int v = 3 * voxel_index(g, c.x, c.y, c.z) + ch;
    float st = sigma_t[v], ss = sigma_s[v];
    if (st <= 0.0f || b <= a) continue;  // a ray through a voxel's edge gives an empty segment
    int n = max(1, (int)ceil((b - a) / (step * g->voxel)));
    float h = (b - a) / n;
    float seg_tr = exp(-st * h);
    reach = 0.0f;
    for (int l = 0; l < light_count; ++l) {
      e0[l] = unattenuated(g, sigma_t, lights, l, g_phase, ch, o + d * (a + FACE_INSET * h), d,
                           bvh, ior, use_mesh, &tau0[l]);
      reach += e0[l];
    }
    for (int k = 0; k < n && tr > 0.0f && (tr > 1e-7f || tr * reach > 1e-6f * radiance); ++k) {
      // The ends' offsets in the sub-step: [u0, u1] within [0, h].
      float u0 = k == 0 ? FACE_INSET * h : 0.0f, u1 = k == n - 1 ? (1.0f - FACE_INSET) * h : h;
      float3 p1 = o + d * (a + k * h + u1);
      float in_scatter = 0.0f;
      for (int l = 0; l < light_count; ++l) {
        float tau1;
        float e1 =
            unattenuated(g, sigma_t, lights, l, g_phase, ch, p1, d, bvh, ior, use_mesh, &tau1);
        if (e0[l] > 0.0f || e1 > 0.0f) {
          // The light's depth, linear through the two ends, at the sub-step's start and its slope.
          // (An optical depth is never negative: where the light's depth is far from linear, a
          // blocker's edge within the sub-step, the extrapolation to the ends must not go below 0.)
          float slope = (tau1 - tau0[l]) / (u1 - u0), start = tau0[l] - slope * u0;
          in_scatter += 0.5f * (e0[l] + e1) *
                        exp_mean(fmax(start, 0.0f), fmax(start + (st + slope) * h, 0.0f));
        }
        e0[l] = e1;
        tau0[l] = tau1;
      }
      radiance += tr * h * ss * in_scatter;
      tr *= seg_tr;
    }
  }
  *tr_end = tr;
  return radiance;
}

typedef struct {
  float3 o, d;
  float w;
  float tmin;  // where the search for the next crossing starts (surface_eps past one)
} Branch;

__kernel void single_march(float3 origin, float voxel, int nx, int ny, int nz,
                           __global const float* sigma_s, __global const float* sigma_t,
                           __global const float* lights, int light_count, float g_phase,
                           __global const float* camera, int width, int height, float step,
                           float ior, int use_mesh, __global const float* bvh_bounds,
                           __global const int* bvh_links, __global const float* bvh_tris,
                           __global float* out) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);  // no bricks: the marcher walks voxels
  Bvh bvh = {bvh_bounds, bvh_links, bvh_tris, 1e-3f * voxel};
  Cam cam = load_camera(camera);
  float3 d0 = camera_ray(cam, x, y, width, height, 0.5f, 0.5f);
  float result[3] = {0.0f, 0.0f, 0.0f};
  for (int ch = 0; ch < 3; ++ch) {
    float tr;
    if (!use_mesh) {  // voxel_boundary, index matched: the grid alone along the whole ray
      result[ch] = march_segment(&g, sigma_s, sigma_t, lights, light_count, g_phase, ch,
                                 cam.position, d0, 0.0f, INFINITY, step, bvh, ior, false, &tr);
      continue;
    }
    Branch stack[16];
    int top = 0, segments = 0;
    stack[top++] = (Branch){cam.position, d0, 1.0f, 0.0f};
    while (top > 0 && segments++ < 64) {
      Branch b = stack[--top];
      if (b.w < 1e-4f) continue;
      float t;
      float3 n;
      bool hit = mesh_hit(bvh, b.o, b.d, b.tmin, INFINITY, &t, &n);
      if (!hit) continue;  // no crossing ahead: outside the mesh, leaving the scene
      bool inside = dot(b.d, n) > 0.0f;  // the crossing ahead leaves the mesh
      if (inside) {
        result[ch] += b.w * march_segment(&g, sigma_s, sigma_t, lights, light_count, g_phase, ch,
                                          b.o, b.d, 0.0f, t, step, bvh, ior, true, &tr);
        b.w *= tr;
      }
      float3 p = b.o + b.d * t;
      float eps = surface_eps(bvh, p);
      if (inside) n = -n;  // face the incident side
      if (ior == 1.0f) {  // index matched: the ray crosses unchanged
        if (top < 15) stack[top++] = (Branch){p, b.d, b.w, eps};
        continue;
      }
      if (top > 13) continue;
      float ct;
      float f = fresnel(-dot(b.d, n), inside ? ior : 1.0f / ior, &ct);
      stack[top++] = (Branch){p, reflect_dir(b.d, n), b.w * f, eps};
      if (f < 1.0f)
        stack[top++] =
            (Branch){p, refract_dir(b.d, n, inside ? ior : 1.0f / ior, ct), b.w * (1.0f - f), eps};
    }
  }
  size_t i = 3 * ((size_t)y * width + x);
  out[i] = result[0];
  out[i + 1] = result[1];
  out[i + 2] = result[2];
}
