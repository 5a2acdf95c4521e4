// Deterministic single-scatter ray marcher: per pixel, the view ray crosses the voxels exactly
// (DDA); inside each voxel the in-scattering integral is summed over sub-steps of at most `step`
// voxels, each weighted by the exact integral of the view transmittance over the sub-step; the
// light's transmittance is the exact optical depth through the voxels. Converges as step -> 0.

__kernel void single_march(float3 origin, float voxel, int nx, int ny, int nz,
                           __global const float* sigma_s, __global const float* sigma_t,
                           __global const float* lights, int light_count, float g_phase,
                           __global const float* camera, int width, int height, float step,
                           __global float* out) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  Grid g;
  g.origin = origin;
  g.voxel = voxel;
  g.nx = nx;
  g.ny = ny;
  g.nz = nz;
  Cam cam = load_camera(camera);
  float3 o = cam.position;
  float3 d = camera_ray(cam, x, y, width, height, 0.5f, 0.5f);
  float result[3] = {0.0f, 0.0f, 0.0f};
  float t0, t1;
  if (grid_interval(&g, o, d, &t0, &t1)) {
    for (int ch = 0; ch < 3; ++ch) {
      Dda s;
      dda_init(&s, o, d, g.origin, g.voxel, (int3)(nx, ny, nz), t0, t1);
      float tr = 1.0f, radiance = 0.0f, a, b;
      int3 c;
      while (dda_next(&s, &a, &b, &c) && tr > 1e-7f) {
        int v = 3 * voxel_index(&g, c.x, c.y, c.z) + ch;
        float st = sigma_t[v], ss = sigma_s[v];
        if (st <= 0.0f) continue;
        int n = max(1, (int)ceil((b - a) / (step * voxel)));
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
            float tau = optical_depth(&g, sigma_t, ch, p, wl, 0.0f, dist);
            in_scatter += e * exp(-tau) * hg_phase(dot(wl, d), g_phase);
          }
          radiance += tr * w * ss * in_scatter;
          tr *= seg_tr;
        }
      }
      result[ch] = radiance;
    }
  }
  size_t i = 3 * ((size_t)y * width + x);
  out[i] = result[0];
  out[i + 1] = result[1];
  out[i + 2] = result[2];
}
