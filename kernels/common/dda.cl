// The voxel medium (piecewise constant: each voxel holds its own sigma_s and sigma_a),
// Amanatides-Woo traversal of a regular grid of cells, exact optical depth. Part of the kernels'
// shared library (pipelines/common/cl_library.hpp).

// ---- The voxel medium -----------------------------------------------------------------------

typedef struct {
  float3 origin;  // corner of voxel (0, 0, 0)
  float voxel;    // edge length
  int nx, ny, nz;
  int brick, bx, by, bz;
} Grid;

Grid make_grid(float3 origin, float voxel, int nx, int ny, int nz, int brick, int bx, int by, int bz) {
  Grid g;
  g.origin = origin;
  g.voxel = voxel;
  g.nx = nx;
  g.ny = ny;
  g.nz = nz;
  g.brick = brick;
  g.bx = bx;
  g.by = by;
  g.bz = bz;
  return g;
}

int voxel_index(const Grid* g, int i, int j, int k) { return (k * g->ny + j) * g->nx + i; }

// sigma of `channel` at voxel (i, j, k); zero outside the grid.
float voxel_sigma(const Grid* g, __global const float* sigma, int3 c, int channel) {
  if (c.x < 0 || c.y < 0 || c.z < 0 || c.x >= g->nx || c.y >= g->ny || c.z >= g->nz) return 0.0f;
  return sigma[3 * voxel_index(g, c.x, c.y, c.z) + channel];
}

int3 voxel_of(const Grid* g, float3 p) {
  float3 q = (p - g->origin) / g->voxel;
  return (int3)((int)floor(q.x), (int)floor(q.y), (int)floor(q.z));
}

// Parametric interval [t0, t1] of the ray inside the grid's box; false if it misses.
bool grid_interval(const Grid* g, float3 o, float3 d, float* t0, float* t1) {
  float3 lo = g->origin;
  float3 hi = g->origin + g->voxel * (float3)(g->nx, g->ny, g->nz);
  float3 inv = 1.0f / d;  // IEEE: +-inf for zero components
  float3 a = (lo - o) * inv, b = (hi - o) * inv;
  float3 mn = fmin(a, b), mx = fmax(a, b);
  // A zero direction component gives nan when the origin lies on a face; fmax/fmin drop nans.
  float n = fmax(fmax(mn.x, mn.y), fmax(mn.z, 0.0f));
  float f = fmin(fmin(mx.x, mx.y), mx.z);
  *t0 = n;
  *t1 = f;
  return f > n;
}

// ---- Amanatides-Woo traversal of a regular grid of cells -------------------------------------

typedef struct {
  int3 cell, step, dims;
  float3 tmax, tdelta;
  float t, tend;
} Dda;

void dda_init(Dda* s, float3 o, float3 d, float3 origin, float cell, int3 dims, float t0, float t1) {
  float3 p = o + d * t0;
  float3 q = (p - origin) / cell;
  s->cell = clamp((int3)((int)floor(q.x), (int)floor(q.y), (int)floor(q.z)), (int3)(0), dims - 1);
  s->dims = dims;
  s->step = (int3)(d.x >= 0 ? 1 : -1, d.y >= 0 ? 1 : -1, d.z >= 0 ? 1 : -1);
  float3 next = origin + cell * (convert_float3(s->cell) + (float3)(d.x >= 0, d.y >= 0, d.z >= 0));
  float3 ad = fabs(d);
  s->tdelta = (float3)(ad.x > 0 ? cell / ad.x : INFINITY, ad.y > 0 ? cell / ad.y : INFINITY,
                       ad.z > 0 ? cell / ad.z : INFINITY);
  s->tmax = (float3)(ad.x > 0 ? (next.x - o.x) / d.x : INFINITY,
                     ad.y > 0 ? (next.y - o.y) / d.y : INFINITY,
                     ad.z > 0 ? (next.z - o.z) / d.z : INFINITY);
  s->t = t0;
  s->tend = t1;
}

// The next cell segment [*a, *b] and its cell; false when the ray has left the grid or passed tend.
bool dda_next(Dda* s, float* a, float* b, int3* cell) {
  if (s->t >= s->tend) return false;
  if (any(s->cell < 0) || any(s->cell >= s->dims)) return false;
  *cell = s->cell;
  *a = s->t;
  float tn = fmin(fmin(s->tmax.x, s->tmax.y), s->tmax.z);
  *b = fmin(tn, s->tend);
  s->t = *b;
  if (s->tmax.x <= tn) { s->cell.x += s->step.x; s->tmax.x += s->tdelta.x; }
  else if (s->tmax.y <= tn) { s->cell.y += s->step.y; s->tmax.y += s->tdelta.y; }
  else { s->cell.z += s->step.z; s->tmax.z += s->tdelta.z; }
  return true;
}

// Exact optical depth of `channel` along o + t d, t in [t0, t1] (piecewise-constant voxels).
// A traversal of the grid's voxels along o + t d over [t0, t1]; false if that misses the grid.
bool dda_over(const Grid* g, float3 o, float3 d, float t0, float t1, Dda* s) {
  float g0, g1;
  if (!grid_interval(g, o, d, &g0, &g1)) return false;
  g0 = fmax(g0, t0);
  g1 = fmin(g1, t1);
  if (g1 <= g0) return false;
  dda_init(s, o, d, g->origin, g->voxel, (int3)(g->nx, g->ny, g->nz), g0, g1);
  return true;
}

float optical_depth(const Grid* g, __global const float* sigma_t, int channel, float3 o, float3 d,
                    float t0, float t1) {
  Dda s;
  if (!dda_over(g, o, d, t0, t1, &s)) return 0.0f;
  float tau = 0.0f, a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) tau += sigma_t[3 * voxel_index(g, c.x, c.y, c.z) + channel] * (b - a);
  return tau;
}

// The three channels' optical depths along one traversal: per channel the same sums, in the same
// order, as optical_depth (a third of its traversals where all three are needed).
float3 optical_depth3(const Grid* g, __global const float* sigma_t, float3 o, float3 d, float t0, float t1) {
  Dda s;
  if (!dda_over(g, o, d, t0, t1, &s)) return (float3)(0.0f);
  float3 tau = (float3)(0.0f);
  float a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) tau += vload3(voxel_index(g, c.x, c.y, c.z), sigma_t) * (b - a);
  return tau;
}

// The part of the segment [a, b] of o + t d on the side n . (x - c) <= w of a voxel's plane
// (n, w; zeros: the whole segment), c the voxel's centre.
float inside_length(float4 plane, float3 c, float3 o, float3 d, float a, float b) {
  float nd = dot(plane.xyz, d);
  float f = dot(plane.xyz, o - c) - plane.w;  // n . (x - c) - w at t = 0
  if (nd > 0.0f) b = fmin(b, -f / nd);
  else if (nd < 0.0f) a = fmax(a, -f / nd);
  else if (f > 0.0f) return 0.0f;
  return fmax(b - a, 0.0f);
}

// optical_depth3 where a voxel's medium may end at a plane (`bound`, 4 floats a voxel: see
// inside_length; pipelines/common/boundary_planes.hpp): each voxel's coefficient times the length
// of the segment on the plane's inside. A null `bound`: optical_depth3 (no plane to read).
float3 optical_depth3_bounded(const Grid* g, __global const float* sigma_t, __global const float* bound,
                              float3 o, float3 d, float t0, float t1) {
  if (bound == 0) return optical_depth3(g, sigma_t, o, d, t0, t1);
  Dda s;
  if (!dda_over(g, o, d, t0, t1, &s)) return (float3)(0.0f);
  float3 tau = (float3)(0.0f);
  float a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    int v = voxel_index(g, c.x, c.y, c.z);
    float4 plane = vload4(v, bound);
    float len = b - a;
    if (plane.x != 0.0f || plane.y != 0.0f || plane.z != 0.0f) {
      float3 centre = g->origin + g->voxel * (convert_float3(c) + 0.5f);
      len = inside_length(plane, centre, o, d, a, b);
    }
    tau += vload3(v, sigma_t) * len;
  }
  return tau;
}
