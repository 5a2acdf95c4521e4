// Shared by the lbl kernels (after kernels/common/: Grid, Dda, lights, camera).
// The material volume: per voxel sigma_s and sigma_t (RGB), the refractive index n (smoothed)
// and its gradient (per scene unit, 3 floats), all on the same grid as the deposit, the lattice
// and the irradiance volume.

// OpenCL 1.2 has no float atomics: add through a compare-and-swap loop on the bits.
void atomic_add_float(volatile __global float* p, float v) {
  union {
    uint u;
    float f;
  } old, next;
  do {
    old.f = *p;
    next.f = old.f + v;
  } while (atomic_cmpxchg((volatile __global uint*)p, old.u, next.u) != old.u);
}

// Trilinear interpolation of `count` interleaved floats per voxel, read at their centres;
// coordinates outside are clamped to the outermost centres.
void trilinear(const Grid* g, __global const float* field, int count, float3 p, float* out) {
  float3 q = (p - g->origin) / g->voxel - 0.5f;
  float3 hi = (float3)(g->nx - 1, g->ny - 1, g->nz - 1);
  q = clamp(q, (float3)(0.0f), hi);
  int3 c0 = convert_int3(floor(q));
  int3 c1 = min(c0 + 1, (int3)(g->nx - 1, g->ny - 1, g->nz - 1));
  float3 f = q - convert_float3(c0);
  for (int k = 0; k < count; ++k) out[k] = 0.0f;
  for (int corner = 0; corner < 8; ++corner) {
    int3 c = (int3)((corner & 1) ? c1.x : c0.x, (corner & 2) ? c1.y : c0.y, (corner & 4) ? c1.z : c0.z);
    float w = ((corner & 1) ? f.x : 1.0f - f.x) * ((corner & 2) ? f.y : 1.0f - f.y) *
              ((corner & 4) ? f.z : 1.0f - f.z);
    __global const float* v = field + count * voxel_index(g, c.x, c.y, c.z);
    for (int k = 0; k < count; ++k) out[k] += w * v[k];
  }
}

bool inside_grid(const Grid* g, int3 c) {
  return c.x >= 0 && c.y >= 0 && c.z >= 0 && c.x < g->nx && c.y < g->ny && c.z < g->nz;
}

// One step of the ray equation d/ds (n dx/ds) = grad n in the paper's form (its eqs. 2, 3) with
// v = n dx/ds: x += (delta / n) v, v += delta grad n. Returns the geometric length of the step.
float eikonal_step(const Grid* g, __global const float* n_field, __global const float* grad_field,
                   float delta, float3* x, float3* v) {
  float n, gr[3];
  trilinear(g, n_field, 1, *x, &n);
  trilinear(g, grad_field, 3, *x, gr);
  float3 x0 = *x;
  *x = x0 + (delta / n) * *v;
  *v = *v + delta * (float3)(gr[0], gr[1], gr[2]);
  return length(*x - x0);
}
