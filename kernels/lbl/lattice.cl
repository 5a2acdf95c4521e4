// Lattice-Boltzmann diffusion of the deposited light: 6 axis directions plus a rest state.
// f holds, per node and direction d (0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z) and channel, the power
// leaving the node along d after the node's collision; layout f[(d * 3 + ch) * N + node].
// A step pulls a_d(r) = f_d(r - c_d) and collides (per channel, coefficients per node):
//   f_d(r) = (1 - pt) a_d + (ps / 6) sum_j a_j + src / 6
// with pt = 1 - exp(-sigma_t dx) and ps = pt sigma_s / sigma_t: every entry is in [0, 1] for any
// density, and without absorption (ps = pt) a step conserves the total. The rest state is the
// source (the power the light rays deposited), emitted evenly in the six directions each step.
// irr(r) = w sum_j a_j is the power scattered in the node per step (w = sigma_s x the mean path
// in the voxel), the multiple-scattering emission the view pass reads.
// Edges: 0 open (nothing comes in), 1 reflecting (a closed box), 2 periodic.

int3 lattice_dir(int d) {
  int s = (d & 1) ? -1 : 1;
  return (int3)(d / 2 == 0 ? s : 0, d / 2 == 1 ? s : 0, d / 2 == 2 ? s : 0);
}

int axis_of(int3 v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); }

void collide(__global const float* pt, __global const float* ps, __global const float* w,
             __global const float* src, size_t node, float a[6][3], float out[6][3],
             float irr[3]) {
#pragma unroll
  for (int ch = 0; ch < 3; ++ch) {
    float sum = a[0][ch] + a[1][ch] + a[2][ch] + a[3][ch] + a[4][ch] + a[5][ch];
    float t = pt[3 * node + ch], s = ps[3 * node + ch];
    float iso = (s * sum + src[3 * node + ch]) * (1.0f / 6.0f);
#pragma unroll
    for (int d = 0; d < 6; ++d) out[d][ch] = (1.0f - t) * a[d][ch] + iso;
    irr[ch] = w[3 * node + ch] * sum;
  }
}

#ifndef LBL_FLUX_CAP
#define LBL_FLUX_CAP 0.3333333f
#endif

// a[d][ch]: what arrives at node r along d, f_d(r - c_d), or at an edge what comes in there.
void pull(const int dims[3], const int edges[3], const int rr[3], size_t node, size_t n,
          __global const float* f_in, float a[6][3]) {
  size_t stride[3] = {1, (size_t)dims[0], (size_t)dims[0] * dims[1]};
#pragma unroll
  for (int d = 0; d < 6; ++d) {
    int axis = d / 2, step = (d & 1) ? -1 : 1;
    int sa = rr[axis] - step, dim = dims[axis], edge = edges[axis];
    // The source node along d, or where a packet comes from at the edge.
    long src_node = (long)node - step * (long)stride[axis];
    int from = d;
    bool none = false;
    if (sa < 0 || sa >= dim) {
      if (edge == 2) src_node += (sa < 0 ? 1 : -1) * (long)dim * (long)stride[axis];
      else if (edge == 1) { src_node = (long)node; from = d ^ 1; }
      else none = true;
    }
#pragma unroll
    for (int ch = 0; ch < 3; ++ch) a[d][ch] = none ? 0.0f : f_in[(from * 3 + ch) * n + src_node];
  }
}

// The direction of the light at each node, m = J / phi (3 floats per node): J the net power
// flow along the axes, the mean of what arrives (a_d) and what leaves (f_d), phi the same
// packets' total, both summed over channels; |m| <= 1. A linearly anisotropic radiance
// L = (phi + 3 J . w) / (4 pi) carried along the 6 axes gives exactly J / phi, so the view pass
// can scatter the lattice's light with the phase's first moment (kernels/lbl/view.cl).
__kernel void lattice_flux(int nx, int ny, int nz, int edge_x, int edge_y, int edge_z,
                           __global const float* f, __global float* flux) {
  int3 r = (int3)(get_global_id(0), get_global_id(1), get_global_id(2));
  if (r.x >= nx || r.y >= ny || r.z >= nz) return;
  int dims[3] = {nx, ny, nz}, edges[3] = {edge_x, edge_y, edge_z}, rr[3] = {r.x, r.y, r.z};
  size_t n = (size_t)nx * ny * nz, node = ((size_t)r.z * ny + r.y) * nx + r.x;
  float a[6][3];
  pull(dims, edges, rr, node, n, f, a);
  float p[6], total = 0.0f;
#pragma unroll
  for (int d = 0; d < 6; ++d) {
    p[d] = 0.0f;
    for (int ch = 0; ch < 3; ++ch) p[d] += 0.5f * (a[d][ch] + f[(d * 3 + ch) * n + node]);
    total += p[d];
  }
  float3 m = total > 0.0f ? (float3)(p[0] - p[1], p[2] - p[3], p[4] - p[5]) / total : (float3)(0.0f);
  float len = length(m);
  if (len > LBL_FLUX_CAP) m *= LBL_FLUX_CAP / len;
  vstore3(m, node, flux);
}

// One step over the whole grid (one work item per node, double-buffered f).
__kernel void lattice_step(int nx, int ny, int nz, int edge_x, int edge_y, int edge_z,
                           __global const float* pt, __global const float* ps,
                           __global const float* w, __global const float* src,
                           __global const float* f_in, __global float* f_out,
                           __global float* irr) {
  int3 r = (int3)(get_global_id(0), get_global_id(1), get_global_id(2));
  if (r.x >= nx || r.y >= ny || r.z >= nz) return;
  int dims[3] = {nx, ny, nz}, edges[3] = {edge_x, edge_y, edge_z}, rr[3] = {r.x, r.y, r.z};
  size_t n = (size_t)nx * ny * nz, node = ((size_t)r.z * ny + r.y) * nx + r.x;
  float a[6][3], out[6][3], e[3];
  pull(dims, edges, rr, node, n, f_in, a);
  collide(pt, ps, w, src, node, a, out, e);
#pragma unroll
  for (int d = 0; d < 6; ++d)
#pragma unroll
    for (int ch = 0; ch < 3; ++ch) f_out[(d * 3 + ch) * n + node] = out[d][ch];
  for (int ch = 0; ch < 3; ++ch) irr[3 * node + ch] = e[ch];
}

#ifdef LBL_B
#define B3 (LBL_B * LBL_B * LBL_B)

// Whether a packet leaving local node l along d leaves the block, and the node's index on the
// face it leaves through (the two other local coordinates).
bool leaves_block(int3 l, int d) {
  int la = axis_of(l + lattice_dir(d), d / 2);
  return la < 0 || la >= LBL_B;
}

int face_index(int3 l, int axis) {
  return axis == 0 ? l.z * LBL_B + l.y : (axis == 1 ? l.z * LBL_B + l.x : l.y * LBL_B + l.x);
}

// Where in the interface buffer block `block` keeps what leaves it along d from local node l.
size_t iface_slot(size_t block, int d, int3 l, int ch) {
  return ((block * 6 + d) * LBL_B * LBL_B + face_index(l, d / 2)) * 3 + ch;
}

// The paper's blocked form: one work group per block of LBL_B^3 nodes keeps f in local memory
// and runs `inner` steps; what leaves through a block face is averaged over those steps into the
// interface buffer (6 faces x LBL_B^2 nodes x 3 channels per block), which the neighbour reads
// as its inflow during the next launch. iface_in and iface_out alternate between launches. With
// inner = 1 this is exactly lattice_step; with more, inflow lags by a launch (the steady state
// is the same). Edges: open or reflecting.
__kernel void lattice_blocked(int nx, int ny, int nz, int edge_x, int edge_y, int edge_z,
                              __global const float* pt, __global const float* ps,
                              __global const float* w, __global const float* src,
                              __global const float* f_in, __global float* f_out,
                              __global float* irr, __global const float* iface_in,
                              __global float* iface_out, int inner) {
  __local float lf[18 * B3];
  int3 l = (int3)(get_local_id(0), get_local_id(1), get_local_id(2));
  int3 blk = (int3)(get_group_id(0), get_group_id(1), get_group_id(2));
  int3 nb = (int3)(nx / LBL_B, ny / LBL_B, nz / LBL_B);
  int3 r = blk * LBL_B + l, edges = (int3)(edge_x, edge_y, edge_z);
  size_t n = (size_t)nx * ny * nz, node = ((size_t)r.z * ny + r.y) * nx + r.x;
  int ln = (l.z * LBL_B + l.y) * LBL_B + l.x;
  size_t block = ((size_t)blk.z * nb.y + blk.y) * nb.x + blk.x;
  for (int k = 0; k < 18; ++k) lf[k * B3 + ln] = f_in[k * n + node];
  // Inflow from outside the block, fixed for this launch: 0 none, 1 interface, 2 reflect.
  int kind[6];
  float ext[6][3], acc[6][3];
  for (int d = 0; d < 6; ++d) {
    int axis = d / 2;
    int3 c = lattice_dir(d);
    kind[d] = 0;
    for (int ch = 0; ch < 3; ++ch) ext[d][ch] = acc[d][ch] = 0.0f;
    if (!leaves_block(l, d ^ 1)) continue;  // the source node is inside the block
    int3 src_blk = blk - c;
    int ba = axis_of(src_blk, axis);
    if (ba >= 0 && ba < axis_of(nb, axis)) {
      kind[d] = 1;
      size_t sb = ((size_t)src_blk.z * nb.y + src_blk.y) * nb.x + src_blk.x;
      for (int ch = 0; ch < 3; ++ch) ext[d][ch] = iface_in[iface_slot(sb, d, l, ch)];
    } else if (axis_of(edges, axis) == 1) {
      kind[d] = 2;
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  float a[6][3], out[6][3], e[3];
  for (int step = 0; step < inner; ++step) {
    for (int d = 0; d < 6; ++d) {
      int3 s = l - lattice_dir(d);
      int sa = axis_of(s, d / 2);
      bool in_block = sa >= 0 && sa < LBL_B;
      int sn = (s.z * LBL_B + s.y) * LBL_B + s.x;
      for (int ch = 0; ch < 3; ++ch)
        a[d][ch] = in_block ? lf[(d * 3 + ch) * B3 + sn]
                            : (kind[d] == 1 ? ext[d][ch]
                                            : (kind[d] == 2 ? lf[((d ^ 1) * 3 + ch) * B3 + ln] : 0.0f));
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    collide(pt, ps, w, src, node, a, out, e);
    for (int d = 0; d < 6; ++d) {
      bool leaves = leaves_block(l, d);
      for (int ch = 0; ch < 3; ++ch) {
        lf[(d * 3 + ch) * B3 + ln] = out[d][ch];
        if (leaves) acc[d][ch] += out[d][ch];
      }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  for (int k = 0; k < 18; ++k) f_out[k * n + node] = lf[k * B3 + ln];
  for (int ch = 0; ch < 3; ++ch) irr[3 * node + ch] = e[ch];
  for (int d = 0; d < 6; ++d)
    if (leaves_block(l, d))
      for (int ch = 0; ch < 3; ++ch) iface_out[iface_slot(block, d, l, ch)] = acc[d][ch] / inner;
}

// Fills the interface buffer from f (what each face node sends out of its block), so that a
// state written from the host is seen by the neighbouring blocks as the global form sees it.
__kernel void lattice_interfaces(int nx, int ny, int nz, __global const float* f,
                                 __global float* iface) {
  int3 l = (int3)(get_local_id(0), get_local_id(1), get_local_id(2));
  int3 blk = (int3)(get_group_id(0), get_group_id(1), get_group_id(2));
  int3 nb = (int3)(nx / LBL_B, ny / LBL_B, nz / LBL_B);
  int3 r = blk * LBL_B + l;
  size_t n = (size_t)nx * ny * nz, node = ((size_t)r.z * ny + r.y) * nx + r.x;
  size_t block = ((size_t)blk.z * nb.y + blk.y) * nb.x + blk.x;
  for (int d = 0; d < 6; ++d)
    if (leaves_block(l, d))
      for (int ch = 0; ch < 3; ++ch) iface[iface_slot(block, d, l, ch)] = f[(d * 3 + ch) * n + node];
}
#endif

// x[i] *= f[i]: the source times the nodes' emission factors (pipelines/lbl/escape.hpp).
__kernel void scale_by(__global float* x, __global const float* f) {
  size_t i = get_global_id(0);
  x[i] *= f[i];
}

// Partial sums of `count` floats: work item i adds elements i, i + items, ... (for the total
// energy; the host adds the partials in double).
__kernel void partial_sums(__global const float* data, ulong count, __global float* partial) {
  size_t i = get_global_id(0), items = get_global_size(0);
  float s = 0.0f;
  for (size_t k = i; k < count; k += items) s += data[k];
  partial[i] = s;
}

// A STREAM-like copy (out[i] = in[i], a float4 per work item) for comparing the lattice step's
// memory traffic with what the device sustains.
__kernel void stream_copy(__global const float4* in, __global float4* out) {
  size_t i = get_global_id(0);
  out[i] = in[i];
}
