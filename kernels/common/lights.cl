// Lights as pack_lights() (pipelines/common/cl_scene) lays them out. Part of the kernels' shared
// library (pipelines/common/cl_library.hpp).

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
