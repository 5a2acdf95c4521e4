// The mesh boundary of the medium: closest hits through the flattened BVH (scene/bvh.hpp), the
// medium's extent along a ray, and, for a dielectric medium (ior != 1), reflection, refraction and
// the Fresnel transmittance of a straight shadow ray. The medium is the density grid inside the
// mesh: a segment of a ray lies inside iff the next mesh crossing after it leaves the mesh
// (dot(d, n) > 0 with outward normals), which does not depend on counting crossings from the
// camera and so survives a crossing lost to rounding. Point and directional lights cannot be
// reached through a refracting surface by a sampled direction, so shadow rays go straight and are
// weighted by (1 - F) at each crossing; view rays and paths refract exactly.

typedef struct {
  __global const float* bounds;  // 8 floats per node
  __global const int* links;     // 2 ints per node
  __global const float* tris;    // 12 floats per triangle
  float eps;                     // the scene's smallest step past a crossing (a voxel's 1e-3)
  // Optional (null: the BVH answers every query): per voxel of `grid` and one more, where its
  // list of overlapping triangles starts in cell_tris (pipelines/reference/cell_triangles.hpp).
  __global const int* cell_first;
  __global const int* cell_tris;
  Grid grid;
  // With the lists: per voxel, how many voxels a ray from it goes before a voxel with a list
  // (CellTriangles::skip), which the walk jumps.
  __global const uchar* cell_skip;
} Bvh;

// How far past a crossing at p the next search starts, so that it does not find the same surface
// again: the scene's step or, far from the origin, a few float32 steps of p. Rays leave a crossing
// from the crossing point itself and track the medium from there, so that no medium is skipped
// (a dense voxel's light comes from within 1e-3 of a voxel of its face).
float surface_eps(Bvh bvh, float3 p) {
  return fmax(bvh.eps, 1e-6f * (fabs(p.x) + fabs(p.y) + fabs(p.z)));
}

// Entry distance of o + t d into box b within [t0, t1], or INFINITY when it misses.
float box_entry(__global const float* b, float3 o, float3 inv, float t0, float t1) {
  float3 lo = (float3)(b[0], b[1], b[2]), hi = (float3)(b[4], b[5], b[6]);
  float3 a = (lo - o) * inv, c = (hi - o) * inv;
  float3 mn = fmin(a, c), mx = fmax(a, c);
  float n = fmax(fmax(mn.x, mn.y), fmax(mn.z, t0));
  float f = fmin(fmin(mx.x, mx.y), fmin(mx.z, t1));
  return n <= f ? n : INFINITY;
}

// Moller-Trumbore: whether o + t d meets triangle `tri` (12 floats) at t in (t0, *best); then
// *best is that t and *normal the triangle's unit normal.
bool triangle_hit(__global const float* tri, float3 o, float3 d, float t0, float* best,
                  float3* normal) {
  float3 v0 = (float3)(tri[0], tri[1], tri[2]);
  float3 e1 = (float3)(tri[4], tri[5], tri[6]) - v0, e2 = (float3)(tri[8], tri[9], tri[10]) - v0;
  float3 p = cross(d, e2);
  float det = dot(e1, p);
  if (fabs(det) < 1e-20f) return false;
  float3 s = o - v0;
  float u = dot(s, p) / det;
  if (u < 0.0f || u > 1.0f) return false;
  float3 q = cross(s, e1);
  float v = dot(d, q) / det;
  if (v < 0.0f || u + v > 1.0f) return false;
  float th = dot(e2, q) / det;
  if (!(th > t0 && th < *best)) return false;
  *best = th;
  *normal = normalize(cross(e1, e2));
  return true;
}

// The closest intersection with t in (t0, t1) through the per-voxel triangle lists: the voxels
// along the ray, nearest first, each testing the triangles that overlap it; a hit within the
// voxel just tested is the closest (any nearer one lies in a voxel already tested, whose list
// holds its triangle), so it ends the walk (`first`: any hit does, as mesh_search's). The grid
// covers the mesh: past it nothing is hit.
// From a voxel with no list within k + 1 voxels of it (bvh.cell_skip) the walk goes on k voxels
// further along the ray (a unit direction moves no more than that in any axis), for k >= 2.
bool cell_search(Bvh bvh, float3 o, float3 d, float t0, float t1, bool first, float* t_hit,
                 float3* normal) {
  const Grid* g = &bvh.grid;
  float best = t1, g0, g1;
  bool found = false;
  *t_hit = t1;
  if (!grid_interval(g, o, d, &g0, &g1)) return false;
  g0 = fmax(g0, t0);
  g1 = fmin(g1, t1);
  if (g1 <= g0) return false;
  Dda s;
  dda_init(&s, o, d, g->origin, g->voxel, (int3)(g->nx, g->ny, g->nz), g0, g1);
  float a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    int v = voxel_index(g, c.x, c.y, c.z);
    int skip = bvh.cell_skip[v];
    if (skip >= 2) {
      float t = a + skip * g->voxel;
      if (t >= g1) break;
      dda_init(&s, o, d, g->origin, g->voxel, (int3)(g->nx, g->ny, g->nz), t, g1);
      continue;
    }
    for (int i = bvh.cell_first[v], end = bvh.cell_first[v + 1]; i < end; ++i)
      if (triangle_hit(bvh.tris + 12 * bvh.cell_tris[i], o, d, t0, &best, normal)) {
        found = true;
        if (first) break;
      }
    if (found && (first || best <= b)) break;
  }
  *t_hit = best;
  return found;
}

// Closest intersection with t in (t0, t1): its distance and the triangle's unit normal (outward
// for a mesh wound counter-clockwise seen from outside, as scene meshes are). Children are
// visited nearer first, and a box entered past the closest hit so far is skipped. `first`: the
// first intersection found ends the search, for a ray that crosses the mesh once in (t0, t1)
// (from inside a convex mesh), where the first found is the closest. With the voxels' triangle
// lists (bvh.cell_first) the voxel walk answers instead (cell_search).
bool mesh_search(Bvh bvh, float3 o, float3 d, float t0, float t1, bool first, float* t_hit,
                 float3* normal) {
  if (bvh.cell_first) return cell_search(bvh, o, d, t0, t1, first, t_hit, normal);
  float3 inv = 1.0f / d;
  int stack[64];
  float entry[64];
  int top = 0;
  float best = t1;
  bool found = false;
  float root = box_entry(bvh.bounds, o, inv, t0, best);
  if (root < INFINITY) {
    stack[top] = 0;
    entry[top++] = root;
  }
  while (top > 0) {
    --top;
    if (entry[top] > best) continue;
    int node = stack[top];
    int a = bvh.links[2 * node], count = bvh.links[2 * node + 1];
    if (count == 0) {
      // Inner node: children node + 1 and a; push the farther first so the nearer pops next.
      float e1 = box_entry(bvh.bounds + 8 * (node + 1), o, inv, t0, best);
      float e2 = box_entry(bvh.bounds + 8 * a, o, inv, t0, best);
      int n1 = node + 1, n2 = a;
      if (e2 < e1) {
        float te = e1;
        e1 = e2;
        e2 = te;
        n1 = a;
        n2 = node + 1;
      }
      if (e2 < INFINITY && top < 63) {
        stack[top] = n2;
        entry[top++] = e2;
      }
      if (e1 < INFINITY && top < 63) {
        stack[top] = n1;
        entry[top++] = e1;
      }
      continue;
    }
    for (int i = 0; i < count; ++i) {
      if (triangle_hit(bvh.tris + 12 * (a + i), o, d, t0, &best, normal)) {
        found = true;
        if (first) {
          *t_hit = best;
          return true;
        }
      }
    }
  }
  *t_hit = best;
  return found;
}

bool mesh_hit(Bvh bvh, float3 o, float3 d, float t0, float t1, float* t_hit, float3* normal) {
  return mesh_search(bvh, o, d, t0, t1, false, t_hit, normal);
}

// The crossing of a ray from inside a convex mesh: the only one ahead, so the first found.
bool mesh_exit(Bvh bvh, float3 o, float3 d, float t0, float t1, float* t_hit, float3* normal) {
  return mesh_search(bvh, o, d, t0, t1, true, t_hit, normal);
}

float3 reflect_dir(float3 d, float3 n) { return d - 2.0f * dot(d, n) * n; }

// Refraction of d through a surface with unit normal n facing the incident side (dot(d, n) < 0),
// eta = n_incident / n_transmitted, cos_t from fresnel().
float3 refract_dir(float3 d, float3 n, float eta, float cos_t) {
  float cos_i = -dot(d, n);
  return normalize(eta * d + (eta * cos_i - cos_t) * n);
}

// How far from p the medium has no boundary (pipelines/reference/inside_grid: interior_depth).
float interior_distance(const Grid* g, __global const uchar* interior, float3 p) {
  int3 c = voxel_of(g, p);
  if (c.x < 0 || c.y < 0 || c.z < 0 || c.x >= g->nx || c.y >= g->ny || c.z >= g->nz) return 0.0f;
  return interior[voxel_index(g, c.x, c.y, c.z)] * g->voxel;
}

// The crossings of the straight segment o + t d, t in (0, tmax), at most this many.
#define MAX_CROSSINGS 32

// Along the shadow segment o + t d, t in (0, dist), from a point inside the medium: the
// transmittance of the three channels through the medium (ratio tracking over the parts inside
// the mesh) times, for a dielectric, (1 - F) at each crossing; `convex`: the first crossing that
// leaves is the last. With no crossing at all, the
// segment is inside only towards a point light (one inside the mesh); towards a directional
// light the point was outside after rounding.
float3 shadow_transmittance(const Medium* md, Bvh bvh, float ior, bool convex, float3 o, float3 d,
                            float dist, Rng* r) {
  float3 tr = (float3)(1.0f);
  float t0 = 0.0f;
  bool any = false;
  for (int k = 0; k < MAX_CROSSINGS && max3(tr) > 0.0f; ++k) {
    float t;
    float3 n;
    // The first search starts at the point itself (a crossing right next to it still counts);
    // later ones step past the crossing just found.
    // From inside a convex mesh the first crossing is the only one: any found is it.
    bool hit = k == 0 && convex ? mesh_exit(bvh, o, d, 0.0f, dist, &t, &n)
                                : mesh_hit(bvh, o, d, k == 0 ? 0.0f : t0 + surface_eps(bvh, o + d * t0),
                                           dist, &t, &n);
    if (!hit) {
      if (!any && !isinf(dist)) tr *= exact_transmittance(md, o, d, dist);
      return tr;
    }
    float c = dot(d, n);  // > 0: leaving the medium, so [t0, t] was inside
    if (c > 0.0f && t > t0) tr *= exact_transmittance(md, o + d * t0, d, t - t0);
    if (ior != 1.0f) {
      float cos_t;
      tr *= 1.0f - fresnel(fabs(c), c > 0.0f ? ior : 1.0f / ior, &cos_t);
    }
    t0 = t;
    any = true;
    if (convex && c > 0.0f) return tr;  // out of a convex mesh for good
    if (c < 0.0f && !isinf(dist)) {
      // Entering again: what lies past t up to the light is inside if no crossing follows.
      float t2;
      float3 n2;
      if (!mesh_hit(bvh, o, d, t0 + surface_eps(bvh, o + d * t0), dist, &t2, &n2)) {
        tr *= exact_transmittance(md, o + d * t0, d, dist - t0);
        return tr;
      }
    }
  }
  return tr;
}

// The optical depth of `channel` along the shadow segment o + t d, t in (0, dist), from a point
// inside the medium, over the parts inside the mesh (as shadow_transmittance), and in *fresnel_tr
// the product of (1 - F) over the crossings for a dielectric (1 when index matched).
float shadow_depth(const Grid* g, __global const float* sigma_t, int channel, Bvh bvh, float ior,
                   float3 o, float3 d, float dist, float* fresnel_tr) {
  float tau = 0.0f, t0 = 0.0f;
  *fresnel_tr = 1.0f;
  for (int k = 0; k < MAX_CROSSINGS; ++k) {
    float t;
    float3 n;
    bool hit =
        mesh_hit(bvh, o, d, k == 0 ? 0.0f : t0 + surface_eps(bvh, o + d * t0), dist, &t, &n);
    if (!hit) {
      // Past the last crossing: inside only if it entered (or, with none, towards a point light).
      bool inside = k == 0 ? !isinf(dist) : false;
      if (inside) tau += optical_depth(g, sigma_t, channel, o, d, t0, dist);
      return tau;
    }
    float c = dot(d, n);
    if (c > 0.0f && t > t0) tau += optical_depth(g, sigma_t, channel, o, d, t0, t);
    if (ior != 1.0f) {
      float cos_t;
      *fresnel_tr *= 1.0f - fresnel(fabs(c), c > 0.0f ? ior : 1.0f / ior, &cos_t);
    }
    t0 = t;
    if (c < 0.0f && !isinf(dist)) {
      float t2;
      float3 n2;
      if (!mesh_hit(bvh, o, d, t0 + surface_eps(bvh, o + d * t0), dist, &t2, &n2))
        return tau + optical_depth(g, sigma_t, channel, o, d, t0, dist);
    }
  }
  return tau;
}
