// The pinhole camera as pack_camera() (pipelines/common/cl_scene) lays it out. Part of the kernels'
// shared library (pipelines/common/cl_library.hpp).

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
