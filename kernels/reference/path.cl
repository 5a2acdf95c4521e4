// Monte Carlo volumetric path tracer: delta tracking in the voxel medium with per-brick majorants,
// next-event estimation to every light with ratio-tracked shadow rays, Henyey-Greenstein
// sampling, Russian roulette on the path weight. Sample s follows colour channel s mod 3 only, so
// chromatic media need no spectral majorants; the host divides each channel by its own count.
//
// With ior != 1 the mesh is a dielectric boundary: paths reflect or refract at it with Fresnel's
// probabilities (total internal reflection included), tracking inside stops at the surface, and
// shadow rays carry the Fresnel transmittance of their crossings (see boundary.cl).
//
// terms: bit 0 adds light scattered once (NEE at the first vertex), bit 1 light scattered more
// than once. Each launch adds `spp` samples per pixel to sum and sum_sq of their channel, from
// which the host takes the mean and its standard error per channel. sum_sq holds the squares
// times `sq_scale` (the inverse of the lights' largest power): a square in float32 overflows
// past radiance 1.8e19 (a 1e12 light of colour 1e6) and underflows below 1e-19 (a 1e-12 light of
// colour 1e-12), while radiance over power keeps to the geometry's range.

// Light arriving at x and scattered into -d, for one channel: sum over the lights.
float next_event(const Grid* g, __global const float* sigma_t, __global const float* majorant,
                 __global const float* lights, int light_count, float g_phase, int ch, float3 x,
                 float3 d, Bvh bvh, float ior, Rng* r) {
  float sum = 0.0f;
  for (int l = 0; l < light_count; ++l) {
    float3 wl;
    float dist;
    float e = light_irradiance(load_light(lights, l), x, ch, &wl, &dist);
    if (e <= 0.0f) continue;
    if (ior != 1.0f) e *= boundary_transmittance(bvh, ior, x, wl, dist);
    if (e <= 0.0f) continue;
    sum += e * ratio_track(g, sigma_t, majorant, ch, x, wl, dist, r) * hg_phase(dot(wl, d), g_phase);
  }
  return sum;
}

__kernel void path_trace(float3 origin, float voxel, int nx, int ny, int nz, int brick, int bx,
                         int by, int bz, __global const float* sigma_s,
                         __global const float* sigma_t, __global const float* majorant,
                         __global const float* lights, int light_count, float g_phase,
                         __global const float* camera, int width, int height, int terms,
                         int spp, int first_sample, uint seed, int max_depth, float ior,
                         __global const float* bvh_bounds, __global const int* bvh_links,
                         __global const float* bvh_tris, float sq_scale, __global float* sum,
                         __global float* sum_sq) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, brick, bx, by, bz);
  Bvh bvh = {bvh_bounds, bvh_links, bvh_tris};
  const bool dielectric = ior != 1.0f;
  Cam cam = load_camera(camera);
  float3 d0 = camera_ray(cam, x, y, width, height, 0.5f, 0.5f);
  float acc[3] = {0, 0, 0}, acc2[3] = {0, 0, 0};
  for (int s = 0; s < spp; ++s) {
    int sample = first_sample + s;
    int ch = sample % 3;
    Rng r = rng_seed((uint)(y * width + x), (uint)sample, seed);
    float3 o = cam.position, d = d0;
    float weight = 1.0f, value = 0.0f;
    bool inside = !dielectric;  // index matched: no boundary, the medium is everywhere it is
    int depth = 0;
    for (int events = 0; events < 4 * max_depth + 64; ++events) {
      float t_surface = INFINITY;
      float3 n;
      // From a point in the volume any crossing counts (tmin 0); after a surface event the origin was
      // already moved off the surface along its normal.
      bool hit = dielectric && mesh_hit(bvh, o, d, 0.0f, INFINITY, &t_surface, &n);
      float t;
      if (inside && delta_track(&g, sigma_t, majorant, ch, o, d, t_surface, &r, &t)) {
        // A real collision: absorb part of the weight, add light scattered here, scatter on.
        o = o + d * t;
        int3 vc = voxel_of(&g, o);
        int v = 3 * voxel_index(&g, vc.x, vc.y, vc.z) + ch;
        float st = sigma_t[v];
        weight *= st > 0.0f ? sigma_s[v] / st : 0.0f;
        if (weight <= 0.0f || ++depth > max_depth) break;
        if ((depth == 1 && (terms & 1)) || (depth > 1 && (terms & 2)))
          value += weight * next_event(&g, sigma_t, majorant, lights, light_count, g_phase, ch, o,
                                       d, bvh, ior, &r);
        if (!(terms & 2)) break;  // single scattering only: the path ends at its first vertex
        d = hg_sample(d, g_phase, &r);
        if (depth >= 3 && weight < 0.25f) {  // Russian roulette on the path weight
          float q = fmax(weight, 0.05f);
          if (rng_uniform(&r) >= q) break;
          weight /= q;
        }
        continue;
      }
      if (!hit) break;  // leaves the scene
      // The surface: reflect or refract with Fresnel's probabilities.
      float3 p = o + d * t_surface;
      if (dot(d, n) > 0.0f) n = -n;  // face the incident side
      float ct;
      float eta = inside ? ior : 1.0f / ior;
      float f = fresnel(-dot(d, n), eta, &ct);
      if (rng_uniform(&r) < f) {
        d = reflect_dir(d, n);
        o = p + n * BOUNDARY_EPS;
      } else {
        d = refract_dir(d, n, eta, ct);
        o = p - n * BOUNDARY_EPS;
        inside = !inside;
      }
    }
    acc[ch] += value;
    acc2[ch] += (value * sq_scale) * value;
  }
  size_t i = 3 * ((size_t)y * width + x);
  for (int c = 0; c < 3; ++c) {
    sum[i + c] += acc[c];
    sum_sq[i + c] += acc2[c];
  }
}
