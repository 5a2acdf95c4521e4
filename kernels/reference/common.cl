// Shared by the reference kernels: random numbers, the voxel medium (piecewise constant: each voxel
// holds its own sigma_s and sigma_a), ray traversal, Henyey-Greenstein phase, Fresnel, lights.

#define PI 3.14159265358979f
#define INV_4PI 0.0795774715459477f

// ---- Random numbers: PCG32, one stream per (pixel, sample, pass, seed) -------------------------

typedef struct { ulong state; } Rng;

uint pcg_next(Rng* r) {
  ulong old = r->state;
  r->state = old * 6364136223846793005UL + 1442695040888963407UL;
  uint xorshifted = (uint)(((old >> 18u) ^ old) >> 27u);
  uint rot = (uint)(old >> 59u);
  return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
}

// Uniform in [0, 1).
float rng_uniform(Rng* r) { return (pcg_next(r) >> 8) * (1.0f / 16777216.0f); }

Rng rng_seed(uint a, uint b, uint c) {
  Rng r;
  r.state = ((ulong)a << 32) ^ ((ulong)b * 0x9E3779B97F4A7C15UL) ^ ((ulong)c * 0xBF58476D1CE4E5B9UL);
  for (int i = 0; i < 4; ++i) pcg_next(&r);
  return r;
}

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
float optical_depth(const Grid* g, __global const float* sigma_t, int channel, float3 o, float3 d,
                    float t0, float t1) {
  float g0, g1;
  if (!grid_interval(g, o, d, &g0, &g1)) return 0.0f;
  g0 = fmax(g0, t0);
  g1 = fmin(g1, t1);
  if (g1 <= g0) return 0.0f;
  Dda s;
  dda_init(&s, o, d, g->origin, g->voxel, (int3)(g->nx, g->ny, g->nz), g0, g1);
  float tau = 0.0f, a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) tau += sigma_t[3 * voxel_index(g, c.x, c.y, c.z) + channel] * (b - a);
  return tau;
}

// ---- Henyey-Greenstein ----------------------------------------------------------------------

float hg_phase(float cos_theta, float g) {
  float d = 1.0f + g * g - 2.0f * g * cos_theta;
  return INV_4PI * (1.0f - g * g) / (d * sqrt(d));
}

void basis(float3 n, float3* u, float3* v) {
  float3 h = fabs(n.x) < 0.9f ? (float3)(1, 0, 0) : (float3)(0, 1, 0);
  *u = normalize(cross(h, n));
  *v = cross(n, *u);
}

// A direction with cosine to `w` distributed as HG(g); stable for |g| -> 1 and g -> 0.
float3 hg_sample(float3 w, float g, Rng* r) {
  float u1 = rng_uniform(r), u2 = rng_uniform(r);
  float cos_t;
  if (fabs(g) < 1e-3f) {
    cos_t = 1.0f - 2.0f * u1;
  } else {
    float s = (1.0f - g * g) / (1.0f - g + 2.0f * g * u1);
    cos_t = (1.0f + g * g - s * s) / (2.0f * g);
  }
  cos_t = clamp(cos_t, -1.0f, 1.0f);
  float sin_t = sqrt(fmax(0.0f, 1.0f - cos_t * cos_t));
  float phi = 2.0f * PI * u2;
  float3 u, v;
  basis(w, &u, &v);
  return normalize(u * (sin_t * cos(phi)) + v * (sin_t * sin(phi)) + w * cos_t);
}

// ---- Fresnel for unpolarised light; eta = n_incident / n_transmitted ------------------------

// Reflectance at an interface for incidence cosine cos_i > 0; 1 for total internal reflection.
float fresnel(float cos_i, float eta, float* cos_t) {
  float sin2_t = eta * eta * fmax(0.0f, 1.0f - cos_i * cos_i);
  if (sin2_t >= 1.0f) {
    *cos_t = 0.0f;
    return 1.0f;
  }
  float ct = sqrt(1.0f - sin2_t);
  *cos_t = ct;
  float rs = (eta * cos_i - ct) / (eta * cos_i + ct);
  float rp = (cos_i - eta * ct) / (cos_i + eta * ct);
  return 0.5f * (rs * rs + rp * rp);
}

// ---- Lights: type 0 point, 1 directional, 2 spot ----------------------------------------------

typedef struct {
  float3 position, direction, power;  // power: colour x intensity (or irradiance)
  float cos_outer, cos_inner;
  int type;
} Light;

Light load_light(__global const float* l, int i) {
  __global const float* p = l + 16 * i;
  Light L;
  L.position = (float3)(p[0], p[1], p[2]);
  L.direction = (float3)(p[3], p[4], p[5]);
  L.power = (float3)(p[6], p[7], p[8]);
  L.cos_outer = p[9];
  L.cos_inner = p[10];
  L.type = (int)p[11];
  return L;
}

float smooth_step(float e0, float e1, float x) {
  if (e1 <= e0) return x >= e0 ? 1.0f : 0.0f;
  float t = clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// Unshadowed irradiance of `channel` at x from the light, the unit direction *wl towards it and
// the distance *dist (infinite for directional lights).
float light_irradiance(Light L, float3 x, int channel, float3* wl, float* dist) {
  float p = channel == 0 ? L.power.x : (channel == 1 ? L.power.y : L.power.z);
  if (L.type == 1) {
    *wl = -L.direction;
    *dist = INFINITY;
    return p;
  }
  float3 d = L.position - x;
  float r2 = fmax(dot(d, d), 1e-12f);
  *dist = sqrt(r2);
  *wl = d / *dist;
  float e = p / r2;
  if (L.type == 2) e *= smooth_step(L.cos_outer, L.cos_inner, dot(-*wl, L.direction));
  return e;
}

// ---- Camera ---------------------------------------------------------------------------------

typedef struct {
  float3 position, forward, right, up;  // right and up scaled by tan(fov/2) (and aspect)
} Cam;

Cam load_camera(__global const float* c) {
  Cam k;
  k.position = (float3)(c[0], c[1], c[2]);
  k.forward = (float3)(c[3], c[4], c[5]);
  k.right = (float3)(c[6], c[7], c[8]);
  k.up = (float3)(c[9], c[10], c[11]);
  return k;
}

// Ray through (x + jx, y + jy) of a W x H image, row 0 at the top; jitter in [0, 1).
float3 camera_ray(Cam k, int x, int y, int w, int h, float jx, float jy) {
  float sx = 2.0f * (x + jx) / w - 1.0f;
  float sy = 1.0f - 2.0f * (y + jy) / h;
  return normalize(k.forward + k.right * sx + k.up * sy);
}

float channel_of(float3 v, int c) { return c == 0 ? v.x : (c == 1 ? v.y : v.z); }

// ---- Tracking in the voxel medium with per-brick majorants -----------------------------------

// Starts a walk over the bricks crossed by o + t d, t < tmax; false if the ray misses the grid.
bool brick_walk(const Grid* g, float3 o, float3 d, float tmax, Dda* s) {
  float g0, g1;
  if (!grid_interval(g, o, d, &g0, &g1)) return false;
  g1 = fmin(g1, tmax);
  if (g1 <= g0) return false;
  dda_init(s, o, d, g->origin, g->voxel * g->brick, (int3)(g->bx, g->by, g->bz), g0, g1);
  return true;
}

// Delta tracking: the first real collision along o + t d, t < tmax, for `channel`. Empty bricks
// are stepped over; within a brick, tentative collisions are drawn with the brick's majorant.
bool delta_track(const Grid* g, __global const float* sigma_t, __global const float* majorant,
                 int channel, float3 o, float3 d, float tmax, Rng* r, float* t_hit) {
  Dda s;
  if (!brick_walk(g, o, d, tmax, &s)) return false;
  float a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    float m = majorant[(c.z * g->by + c.y) * g->bx + c.x];
    if (m <= 0.0f) continue;
    float t = a;
    for (;;) {
      t -= log(1.0f - rng_uniform(r)) / m;
      if (t >= b) break;
      float sig = voxel_sigma(g, sigma_t, voxel_of(g, o + d * t), channel);
      if (rng_uniform(r) * m < sig) {
        *t_hit = t;
        return true;
      }
    }
  }
  return false;
}

// Ratio tracking: an unbiased estimate of the transmittance along o + t d, t in [0, tmax], with
// Russian roulette once it is small so dense media end early.
float ratio_track(const Grid* g, __global const float* sigma_t, __global const float* majorant,
                  int channel, float3 o, float3 d, float tmax, Rng* r) {
  Dda s;
  if (!brick_walk(g, o, d, tmax, &s)) return 1.0f;
  float tr = 1.0f, a, b;
  int3 c;
  while (dda_next(&s, &a, &b, &c)) {
    float m = majorant[(c.z * g->by + c.y) * g->bx + c.x];
    if (m <= 0.0f) continue;
    float t = a;
    for (;;) {
      t -= log(1.0f - rng_uniform(r)) / m;
      if (t >= b) break;
      tr *= 1.0f - voxel_sigma(g, sigma_t, voxel_of(g, o + d * t), channel) / m;
      if (tr < 0.01f) {
        if (tr <= 0.0f || rng_uniform(r) >= 0.5f) return 0.0f;
        tr *= 2.0f;
      }
    }
  }
  return tr;
}
