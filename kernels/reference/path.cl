// Monte Carlo volumetric path tracer: spectral delta tracking in the voxel medium with per-brick
// majorants (kernels/common/tracking.cl: every path carries the three colour channels with their
// own weights), next-event estimation to every light with shadow rays whose transmittance is
// exact (summed voxel by voxel), Henyey-Greenstein sampling, Russian roulette on the path's
// largest weight.
//
// The medium is the density grid inside the mesh (boundary.cl): tracking stops at every mesh
// crossing, and a segment is tracked only if it lies inside. With ior != 1 the mesh is also a
// dielectric boundary: paths reflect or refract at it with Fresnel's probabilities (total internal
// reflection included) and shadow rays carry the Fresnel transmittance of their crossings.
//
// The samples of a pixel come in batches of `batch`: within a batch each flight's first
// tentative collision with (usually) its real-or-null decision and each scattering direction are
// stratified (padded Owen-scrambled Sobol, kernels/common/rng.cl), the rest (later tentative
// collisions, roulette, Fresnel) independent; batches are independent of each other. batch 1:
// independent samples.
//
// terms: bit 0 adds light scattered once (NEE at the first vertex), bit 1 light scattered more
// than once. Each launch adds `spp` samples per pixel to sum and sum_sq (three channels each),
// and each batch it completes to batch_sq (its sum's square; `part` holds the open batch's sum),
// from which the host takes the mean and its standard error: stratified samples' own variance
// overstates the mean's, the batches' spread does not. sum_sq and batch_sq hold the squares times
// `sq_scale` (the inverse of the lights' largest power): a square in float32 overflows past
// radiance 1.8e19 (a 1e12 light of colour 1e6) and underflows below 1e-19 (a 1e-12 light of
// colour 1e-12), while radiance over power keeps to the geometry's range.

float3 light_irradiance3(Light L, float3 x, float3* wl, float* dist) {
  return (float3)(light_irradiance(L, x, 0, wl, dist), light_irradiance(L, x, 1, wl, dist),
                  light_irradiance(L, x, 2, wl, dist));
}

// The exit maps of the lights (pipelines/reference/exit_maps.hpp): per light a
// header, the cells' list starts and the lists.
typedef struct {
  __global const float* header;
  __global const int* first;
  __global const int* tris;
} ExitMaps;

// The exit of x + t wl from inside a convex mesh through light l's map: the first hit ahead
// among the triangles of x's cell (the only one: a convex mesh is left once); false when the
// light has no map or the cell holds no hit. A point or spot light's map is a perspective from
// the light (pipelines/reference/exit_maps.hpp).
bool exit_map_hit(ExitMaps maps, Bvh bvh, int l, float3 x, float3 wl, float* t, float3* n) {
  __global const float* h = maps.header + 16 * l;
  int nu = (int)h[9], nv = (int)h[10];
  if (nu == 0) return false;
  float3 e1 = vload3(0, h), e2 = vload3(1, h), q = x;
  float z = 1.0f;
  if (h[15] > 0.0f) {
    q = x - vload3(4, h);
    z = dot(q, cross(e1, e2));
    if (!(z > 0.0f)) return false;
  }
  int i = (int)floor((dot(q, e1) / z - h[6]) * h[8]);
  int j = (int)floor((dot(q, e2) / z - h[7]) * h[8]);
  if (i < 0 || j < 0 || i >= nu || j >= nv) return false;
  int c = as_int(h[11]) + j * nu + i;  // (an int's bits)
  float best = INFINITY;
  bool found = false;
  for (int k = maps.first[c], end = maps.first[c + 1]; k < end && !found; ++k)
    found = triangle_hit(bvh.tris + 12 * maps.tris[k], x, wl, 0.0f, &best, n);
  *t = best;
  return found;
}

// Light arriving at x and scattered into -d, per channel: sum over the lights.
float3 next_event(const Medium* md, __global const float* lights, int light_count, float g_phase,
                  float3 x, float3 d, Bvh bvh, ExitMaps maps, float ior, bool use_mesh,
                  bool convex, float interior, Rng* r) {
  float3 sum = (float3)(0.0f);
  for (int l = 0; l < light_count; ++l) {
    float3 wl;
    float dist;
    float3 e = light_irradiance3(load_light(lights, l), x, &wl, &dist);
    if (max3(e) <= 0.0f) continue;
    float t_exit;
    float3 n;
    if (!use_mesh) {
      e *= exact_transmittance(md, x, wl, dist);
    } else if (convex && maps.tris && exit_map_hit(maps, bvh, l, x, wl, &t_exit, &n) &&
               t_exit < dist) {
      // The only crossing (convex), found in the light's map: the medium up to it, and with a
      // dielectric its Fresnel transmittance (leaving: dot(wl, n) > 0).
      e *= exact_transmittance(md, x, wl, t_exit);
      if (ior != 1.0f) {
        float cos_t;
        e *= 1.0f - fresnel(fabs(dot(wl, n)), ior, &cos_t);
      }
    } else {
      // Within `interior` of x there is no boundary: track that far without the mesh.
      float s = fmin(interior, dist);
      if (s > 0.0f) e *= exact_transmittance(md, x, wl, s);
      if (s < dist && max3(e) > 0.0f)
        e *= shadow_transmittance(md, bvh, ior, convex, x + wl * s, wl, dist - s, r);
    }
    if (max3(e) <= 0.0f) continue;
    sum += e * hg_phase(dot(wl, d), g_phase);
  }
  return sum;
}

__kernel void path_trace(float3 origin, float voxel, int nx, int ny, int nz, int brick, int bx,
                         int by, int bz, __global const float* sigma_s,
                         __global const float* sigma_t, __global const float* majorant,
                         __global const int* uniform, int homogeneous,
                         __global const float* lights, int light_count, float g_phase,
                         __global const float* camera, int width, int height, int terms,
                         int spp, int first_sample, uint seed, int max_depth, float ior,
                         int use_mesh, int convex, __global const uchar* interior,
                         __global const float* bvh_bounds, __global const int* bvh_links,
                         __global const float* bvh_tris, int cells,
                         __global const int* cell_first, __global const int* cell_tris,
                         __global const uchar* cell_skip, int exit_maps,
                         __global const float* exit_header, __global const int* exit_first,
                         __global const int* exit_tris, int batch, float sq_scale, __global float* sum,
                         __global float* sum_sq, __global float* part,
                         __global float* batch_sq) {
  int x = get_global_id(0), y = get_global_id(1);
  if (x >= width || y >= height) return;
  Medium md = {make_grid(origin, voxel, nx, ny, nz, brick, bx, by, bz), sigma_s, sigma_t, majorant,
               uniform, homogeneous};
  const Grid* g = &md.g;
  // cells: the mesh queries walk the voxels' triangle lists instead of the BVH (boundary.cl).
  Bvh bvh = {bvh_bounds, bvh_links, bvh_tris, 1e-3f * voxel, cells ? cell_first : 0,
             cell_tris, md.g, cell_skip};
  ExitMaps maps = {exit_header, exit_first, exit_maps ? exit_tris : 0};
  Cam cam = load_camera(camera);
  float3 d0 = camera_ray(cam, x, y, width, height, 0.5f, 0.5f);
  size_t i = 3 * ((size_t)y * width + x);
  float3 acc = (float3)(0.0f), acc2 = (float3)(0.0f), bacc2 = (float3)(0.0f);
  float3 open_sum = vload3(0, part + i);  // the open batch's sum so far
  // Every sample's view ray is the pixel centre's: its first crossing and, index matched (the
  // ray goes on unchanged), the one after it are found once for all samples.
  float view_t[2] = {INFINITY, INFINITY};
  float3 view_n[2] = {(float3)(0.0f), (float3)(0.0f)};
  bool view_hit[2] = {false, false};
  if (use_mesh) {
    view_hit[0] = mesh_hit(bvh, cam.position, d0, 0.0f, INFINITY, &view_t[0], &view_n[0]);
    float3 p = cam.position + d0 * view_t[0];
    if (view_hit[0] && ior == 1.0f)
      view_hit[1] = mesh_hit(bvh, p, d0, surface_eps(bvh, p), INFINITY, &view_t[1], &view_n[1]);
  }
  for (int s = 0; s < spp; ++s) {
    int sample = first_sample + s;
    Rng r = rng_seed((uint)(y * width + x), (uint)sample, seed);
    Sampler sp = sampler_start((uint)(y * width + x), (uint)(sample % batch),
                               mix32(seed ^ mix32((uint)(sample / batch))));
    // To the first tentative collision (delta_track), and the next draw, which is that
    // collision's real-or-null decision unless the flight has none (a grey medium's is always
    // real); else roulette or Fresnel takes it: uniform either way.
    float2 f = sampler_2d(&sp);
    float tau = exp_depth(f.x);
    rng_offer(&r, f.y);
    float3 o = cam.position, d = d0;
    float3 weight = (float3)(1.0f), value = (float3)(0.0f);
    int depth = 0;
    float safe = 0.0f;  // at a vertex: how far the medium has no boundary
    float tmin = 0.0f;  // at a crossing: where the next search starts (surface_eps)
    for (int events = 0; events < 4 * max_depth + 64; ++events) {
      float t_surface = INFINITY, t;
      float3 n;
      bool hit = false, inside = true, collided = false;
      // Within `safe` the flight needs no mesh. A free flight is memoryless: past it, it goes on
      // from there, again without the mesh as far as the distance field there allows.
      while (safe > 0.0f) {
        collided = delta_track(&md, o, d, safe, &weight, &r, &tau, &t);
        if (collided) break;
        o = o + d * safe;
        safe = interior_distance(g, interior, o);
      }
      if (!collided) {
        // From a point in the volume any crossing counts (tmin 0); after a surface event the
        // path leaves from the crossing itself and skips surface_eps of search. Without the mesh
        // (voxel_boundary, index matched) the medium is the grid alone. From a collision inside
        // a convex mesh the crossing ahead is the only one (mesh_exit).
        if (depth == 0 && (events == 0 || (events == 1 && ior == 1.0f))) {
          hit = view_hit[events];  // still on the view ray (above)
          t_surface = view_t[events];
          n = view_n[events];
        } else {
          hit = use_mesh && (convex && depth > 0 && tmin == 0.0f
                                 ? mesh_exit(bvh, o, d, 0.0f, INFINITY, &t_surface, &n)
                                 : mesh_hit(bvh, o, d, tmin, INFINITY, &t_surface, &n));
        }
        if (use_mesh && !hit) break;  // a ray with no crossing ahead is outside the mesh
        // Inside iff the crossing ahead leaves the mesh.
        inside = !use_mesh || dot(d, n) > 0.0f;
        collided = inside && delta_track(&md, o, d, t_surface, &weight, &r, &tau, &t);
      }
      safe = 0.0f;
      tmin = 0.0f;
      if (collided) {
        // A real collision (weights already scaled by the albedo): add light scattered here,
        // scatter on.
        o = o + d * t;
        if (use_mesh) safe = interior_distance(g, interior, o);
        if (max3(weight) <= 0.0f || ++depth > max_depth) break;
        if ((depth == 1 && (terms & 1)) || (depth > 1 && (terms & 2)))
          value += weight * next_event(&md, lights, light_count, g_phase, o, d, bvh, maps, ior,
                                       use_mesh, convex, safe, &r);
        if (!(terms & 2)) break;  // single scattering only: the path ends at its first vertex
        float2 u = sampler_2d(&sp);
        d = hg_sample_u(d, g_phase, u.x, u.y);
        f = sampler_2d(&sp);
        tau = exp_depth(f.x);
        rng_offer(&r, f.y);
        float top = max3(weight);
        if (depth >= 3 && top < 0.25f) {  // Russian roulette on the largest channel's weight
          float q = fmax(top, 0.05f);
          if (rng_uniform(&r) >= q) break;
          weight /= q;
        }
        continue;
      }
      if (!hit || max3(weight) <= 0.0f) break;
      float3 p = o + d * t_surface;
      if (inside) n = -n;  // face the incident side
      if (ior == 1.0f) {  // index matched: the path crosses unchanged
        if (convex && inside) break;  // out of a convex mesh for good
        o = p;
        tmin = surface_eps(bvh, p);
        continue;
      }
      // A dielectric surface: reflect or refract with Fresnel's probabilities.
      float ct;
      float eta = inside ? ior : 1.0f / ior;
      float f = fresnel(-dot(d, n), eta, &ct);
      if (rng_uniform(&r) < f) {
        d = reflect_dir(d, n);
      } else {
        if (convex && inside) break;  // out of a convex mesh for good
        d = refract_dir(d, n, eta, ct);
      }
      o = p;
      tmin = surface_eps(bvh, p);
    }
    acc += value;
    acc2 += (value * sq_scale) * value;
    open_sum += value;
    if ((sample + 1) % batch == 0) {
      bacc2 += (open_sum * sq_scale) * open_sum;
      open_sum = (float3)(0.0f);
    }
  }
  vstore3(open_sum, 0, part + i);
  vstore3(vload3(0, batch_sq + i) + bacc2, 0, batch_sq + i);
  sum[i] += acc.x;
  sum[i + 1] += acc.y;
  sum[i + 2] += acc.z;
  sum_sq[i] += acc2.x;
  sum_sq[i + 1] += acc2.y;
  sum_sq[i + 2] += acc2.z;
}
