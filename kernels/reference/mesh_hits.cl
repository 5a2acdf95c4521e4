// The mesh queries of boundary.cl for a batch of rays, for tests that compare the BVH with the
// per-voxel triangle lists (cells): per ray (o.xyz, t0, d.xyz, pad) the closest hit's distance
// in (t0, inf) (-1 for none) and the triangle's normal, 4 floats each.

__kernel void mesh_hits(float3 origin, float voxel, int nx, int ny, int nz,
                        __global const float* bvh_bounds, __global const int* bvh_links,
                        __global const float* bvh_tris, int cells, __global const int* cell_first,
                        __global const int* cell_tris, __global const uchar* cell_skip,
                        __global const float* rays,
                        __global float* hits) {
  int i = get_global_id(0);
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, nx, ny, nz);
  Bvh bvh = {bvh_bounds, bvh_links, bvh_tris, 1e-3f * voxel, cells ? cell_first : 0, cell_tris,
             g, cell_skip};
  __global const float* r = rays + 8 * i;
  float3 o = (float3)(r[0], r[1], r[2]), d = (float3)(r[4], r[5], r[6]);
  float t;
  float3 n = (float3)(0.0f);
  bool hit = mesh_hit(bvh, o, d, r[3], INFINITY, &t, &n);
  hits[4 * i] = hit ? t : -1.0f;
  hits[4 * i + 1] = n.x;
  hits[4 * i + 2] = n.y;
  hits[4 * i + 3] = n.z;
}
