// Deterministic single-scatter ray marcher: per pixel, the view ray crosses the voxels exactly
// (DDA); inside each voxel the in-scattering integral is summed over sub-steps of at most `step`
// voxels, each weighted by the exact integral of the view transmittance over the sub-step; the
// light's transmittance is the exact optical depth through the voxels. Converges as step -> 0.
//
// With a dielectric boundary (ior != 1) the view ray is split at every surface crossing into its
// reflected and refracted parts, weighted by Fresnel, and each part inside the medium is marched
// up to the surface (a small stack, until the weight is negligible); light reaches a point inside
// along a straight shadow ray weighted by the Fresnel transmittance of the crossings.

// Single-scattered radiance along o + t d, t in [t0, t1], for one channel; *tr_end receives the
// view transmittance from t0 to t1.
float march_segment(const Grid* g, __global const float* sigma_s, __global const float* sigma_t,
                    __global const float* lights, int light_count, float g_phase, int ch,
                    float3 o, float3 d, float t0, float t1, float step, Bvh bvh, float ior,
                    float* tr_end) {
  float a0, a1;
  *tr_end = 1.0f;
  if (!grid_interval(g, o, d, &a0, &a1)) return 0.0f;
  a0 = fmax(a0, t0);
  a1 = fmin(a1, t1);
  if (a1 <= a0) return 0.0f;
  Dda s;
  dda_init(&s, o, d, g->origin, g->voxel, (int3)(g->nx, g->ny, g->nz), a0, a1);
  float tr = 1.0f, radiance = 0.0f, a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c) && tr > 1e-7f) {
    int v = 3 * voxel_index(g, c.x, c.y, c.z) + ch;
    float st = sigma_t[v], ss = sigma_s[v];
    if (st <= 0.0f) continue;
    int n = max(1, (int)ceil((b - a) / (step * g->voxel)));
    float h = (b - a) / n;
    float seg_tr = exp(-st * h);
    // Integral of exp(-st u) over [0, h], stable for small st h.
    float w = st * h > 1e-4f ? (1.0f - seg_tr) / st : h * (1.0f - 0.5f * st * h);
    for (int k = 0; k < n; ++k) {
      float3 p = o + d * (a + (k + 0.5f) * h);
      float in_scatter = 0.0f;
      for (int l = 0; l < light_count; ++l) {
        float3 wl;
        float dist;
        float e = light_irradiance(load_light(lights, l), p, ch, &wl, &dist);
        if (e <= 0.0f) continue;
        float tau = optical_depth(g, sigma_t, ch, p, wl, 0.0f, dist);
        if (ior != 1.0f) e *= boundary_transmittance(bvh, ior, p, wl, dist);
        in_scatter += e * exp(-tau) * hg_phase(dot(wl, d), g_phase);
      }
      radiance += tr * w * ss * in_scatter;
      tr *= seg_tr;
    }
  }
  *tr_end = tr;
  return radiance;
}

typedef struct {
  float3 o, d;
  float w;
  int inside;
} Branch;

__kernel void single_march(float3 origin, float voxel, int nx, int ny, int nz,
                           __global const float* sigma_s, __global const float* sigma_t,
                           __global const float* lights, int light_count, float g_phase,
                           __global const float* camera, int width, int height, float step,
                           float ior, __global const float* bvh_bounds,
                           __global const int* bvh_links, __global const float* bvh_tris,
                           __global float* out) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);  // no bricks: the marcher walks voxels
  Bvh bvh = {bvh_bounds, bvh_links, bvh_tris};
  Cam cam = load_camera(camera);
  float3 d0 = camera_ray(cam, x, y, width, height, 0.5f, 0.5f);
  float result[3] = {0.0f, 0.0f, 0.0f};
  for (int ch = 0; ch < 3; ++ch) {
    float tr;
    if (ior == 1.0f) {
      result[ch] = march_segment(&g, sigma_s, sigma_t, lights, light_count, g_phase, ch,
                                 cam.position, d0, 0.0f, INFINITY, step, bvh, ior, &tr);
      continue;
    }
    Branch stack[16];
    int top = 0, segments = 0;
    stack[top++] = (Branch){cam.position, d0, 1.0f, 0};
    while (top > 0 && segments++ < 64) {
      Branch b = stack[--top];
      if (b.w < 1e-4f) continue;
      float t;
      float3 n;
      bool hit = mesh_hit(bvh, b.o, b.d, 0.0f, INFINITY, &t, &n);  // origins sit off the surface
      if (b.inside) {
        result[ch] += b.w * march_segment(&g, sigma_s, sigma_t, lights, light_count, g_phase, ch,
                                          b.o, b.d, 0.0f, hit ? t : INFINITY, step, bvh, ior, &tr);
        b.w *= tr;
      }
      if (!hit || top > 13) continue;
      float3 p = b.o + b.d * t;
      if (dot(b.d, n) > 0.0f) n = -n;  // face the incident side
      float ct;
      float f = fresnel(-dot(b.d, n), b.inside ? ior : 1.0f / ior, &ct);
      stack[top++] = (Branch){p + n * BOUNDARY_EPS, reflect_dir(b.d, n), b.w * f, b.inside};
      if (f < 1.0f)
        stack[top++] = (Branch){p - n * BOUNDARY_EPS,
                                refract_dir(b.d, n, b.inside ? ior : 1.0f / ior, ct),
                                b.w * (1.0f - f), !b.inside};
    }
  }
  size_t i = 3 * ((size_t)y * width + x);
  out[i] = result[0];
  out[i + 1] = result[1];
  out[i + 2] = result[2];
}
