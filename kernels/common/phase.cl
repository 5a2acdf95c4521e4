// Henyey-Greenstein phase and its sampling; after rng.cl. Part of the kernels' shared library
// (pipelines/common/cl_library.hpp).

#define PI 3.14159265358979f
#define INV_4PI 0.0795774715459477f

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

// A direction with cosine to `w` distributed as HG(g), from two uniforms (u1 the cosine's, u2 the
// azimuth's); stable for |g| -> 1 and g -> 0.
float3 hg_sample_u(float3 w, float g, float u1, float u2) {
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

float3 hg_sample(float3 w, float g, Rng* r) {
  float u1 = rng_uniform(r);
  return hg_sample_u(w, g, u1, rng_uniform(r));
}
