// The 18-direction lattice (Geist et al.'s original: the 6 axis neighbours and the 12 in-plane
// diagonals) plus the rest state, global form only. Layout f[(d * 3 + ch) * N + node]; d ^ 1 is
// d's opposite. A diagonal packet crosses sqrt(2) voxels per step, so it has its own collision
// chances (pt_d, ps_d = 1 - exp(-sigma_t' sqrt(2) dx) and its scattering part) and scattered-power
// weight w_d. What scatters, and the source, go to the 18 directions evenly (their second moment
// is isotropic, so diffusion is); per channel:
//   f_d(r) = (1 - pt_type(d)) a_d + (sum_j ps_type(j) a_j + src) / 18
// Edges: 0 open, 1 reflecting (specular: the packet that left towards the wall comes back with
// that component negated), 2 periodic.

__constant int3 kDirs18[18] = {
    (int3)(1, 0, 0),  (int3)(-1, 0, 0),  (int3)(0, 1, 0),  (int3)(0, -1, 0), (int3)(0, 0, 1),
    (int3)(0, 0, -1), (int3)(1, 1, 0),   (int3)(-1, -1, 0), (int3)(1, -1, 0), (int3)(-1, 1, 0),
    (int3)(1, 0, 1),  (int3)(-1, 0, -1), (int3)(1, 0, -1),  (int3)(-1, 0, 1), (int3)(0, 1, 1),
    (int3)(0, -1, -1), (int3)(0, 1, -1), (int3)(0, -1, 1)};

// kMirror18[a][d]: the direction d with its component along axis a negated.
__constant int kMirror18[3][18] = {
    {1, 0, 2, 3, 4, 5, 9, 8, 7, 6, 13, 12, 11, 10, 14, 15, 16, 17},
    {0, 1, 3, 2, 4, 5, 8, 9, 6, 7, 10, 11, 12, 13, 17, 16, 15, 14},
    {0, 1, 2, 3, 5, 4, 6, 7, 8, 9, 12, 13, 10, 11, 16, 17, 14, 15}};

__kernel void lattice18_step(int nx, int ny, int nz, int edge_x, int edge_y, int edge_z,
                             __global const float* pt, __global const float* ps,
                             __global const float* w, __global const float* pt_d,
                             __global const float* ps_d, __global const float* w_d,
                             __global const float* src_power, __global const float* f_in,
                             __global float* f_out, __global float* irr) {
  int3 r = (int3)(get_global_id(0), get_global_id(1), get_global_id(2));
  if (r.x >= nx || r.y >= ny || r.z >= nz) return;
  int dims[3] = {nx, ny, nz}, edges[3] = {edge_x, edge_y, edge_z};
  size_t n = (size_t)nx * ny * nz, node = ((size_t)r.z * ny + r.y) * nx + r.x;
  // Per direction: the element of f (direction and node, channel 0) the arriving packet is, or
  // -1 when nothing arrives.
  long src[18];
#pragma unroll
  for (int d = 0; d < 18; ++d) {
    int3 c = kDirs18[d];
    int s[3] = {r.x - c.x, r.y - c.y, r.z - c.z}, rr[3] = {r.x, r.y, r.z};
    int from = d;  // the direction the packet left its source node along
    bool lost = false;
#pragma unroll
    for (int axis = 0; axis < 3; ++axis) {
      if (s[axis] >= 0 && s[axis] < dims[axis]) continue;
      if (edges[axis] == 2) {
        s[axis] = (s[axis] + dims[axis]) % dims[axis];
      } else if (edges[axis] == 1) {
        s[axis] = rr[axis];  // left towards the wall from here along this axis, came back
        from = kMirror18[axis][from];
      } else {
        lost = true;
      }
    }
    src[d] = lost ? -1 : (long)(from * 3) * (long)n + (long)(((size_t)s[2] * ny + s[1]) * nx + s[0]);
  }
  // One channel at a time keeps 18 arrivals live rather than 54.
  for (int ch = 0; ch < 3; ++ch) {
    float a[18];
#pragma unroll
    for (int d = 0; d < 18; ++d) a[d] = src[d] < 0 ? 0.0f : f_in[src[d] + (long)ch * n];
    size_t k = 3 * node + ch;
    float sum_a = 0.0f, sum_d = 0.0f;
#pragma unroll
    for (int d = 0; d < 6; ++d) sum_a += a[d];
#pragma unroll
    for (int d = 6; d < 18; ++d) sum_d += a[d];
    float iso = (ps[k] * sum_a + ps_d[k] * sum_d + src_power[k]) * (1.0f / 18.0f);
    float keep_a = 1.0f - pt[k], keep_d = 1.0f - pt_d[k];
#pragma unroll
    for (int d = 0; d < 18; ++d) f_out[(d * 3 + ch) * n + node] = (d < 6 ? keep_a : keep_d) * a[d] + iso;
    irr[k] = w[k] * sum_a + w_d[k] * sum_d;
  }
}
