// Plane-parallel slab, infinite in x and y, z in [0, tau] in units of the mean free path
// (sigma_t = 1), lit from z < 0 by a collimated beam at incidence cosine mu0. The medium has index
// `ior`, the outside 1. Photons carry a weight: absorption multiplies it by the albedo (survival
// biasing) and Russian roulette ends light ones. The phase function, Fresnel and random numbers
// are those of common.cl, shared with the path tracer.
//
// Tallies per work item (sums over its photons of the escaping weight, and of its square):
//   0,1 reflected after >= 1 scattering   2,3 transmitted after >= 1 scattering
//   4,5 transmitted unscattered           6,7 reflected unscattered (after internal bounces)
//   8,9 reflected after exactly 1        10,11 transmitted after exactly 1
//   12,13 still inside after the step bound (lost)

#define SLAB_TALLIES 14
#define SLAB_MAX_EVENTS 100000

__kernel void slab_trace(float tau, float albedo, float g, float mu0, float ior, int photons,
                         uint seed, __global float* tallies) {
  int id = get_global_id(0);
  float acc[SLAB_TALLIES];
  for (int k = 0; k < SLAB_TALLIES; ++k) acc[k] = 0.0f;
  float cos_t;
  float r_front = ior != 1.0f ? fresnel(mu0, 1.0f / ior, &cos_t) : 0.0f;
  if (ior == 1.0f) cos_t = mu0;
  float sin_t = sqrt(fmax(0.0f, 1.0f - cos_t * cos_t));
  for (int n = 0; n < photons; ++n) {
    Rng r = rng_seed((uint)id, (uint)n, seed);
    float3 p = (float3)(0.0f, 0.0f, 0.0f);
    float3 d = (float3)(sin_t, 0.0f, cos_t);  // refracted into the slab
    float w = 1.0f - r_front;                 // the specular part is taken analytically
    int scatterings = 0;
    bool done = false;
    for (int events = 0; events < SLAB_MAX_EVENTS && !done; ++events) {
      float s = -log(1.0f - rng_uniform(&r));
      float z = p.z + s * d.z;
      if (z < 0.0f || z > tau) {
        // Reaches a face: leave through it, or reflect internally with Fresnel's probability.
        bool top = z < 0.0f;
        float t_face = (top ? -p.z : tau - p.z) / d.z;
        p = p + d * t_face;
        p.z = top ? 0.0f : tau;
        float ct;
        float rf = ior != 1.0f ? fresnel(fabs(d.z), ior, &ct) : 0.0f;
        if (rf > 0.0f && rng_uniform(&r) < rf) {
          d.z = -d.z;
          continue;
        }
        int slot = top ? (scatterings > 0 ? 0 : 6) : (scatterings > 0 ? 2 : 4);
        acc[slot] += w;
        acc[slot + 1] += w * w;
        if (scatterings == 1) {
          acc[top ? 8 : 10] += w;
          acc[top ? 9 : 11] += w * w;
        }
        done = true;
        break;
      }
      p = p + d * s;
      w *= albedo;
      ++scatterings;
      if (w < 1e-4f) {  // Russian roulette
        if (w <= 0.0f || rng_uniform(&r) >= 0.1f) {
          done = true;
          break;
        }
        w *= 10.0f;
      }
      d = hg_sample(d, g, &r);
    }
    if (!done) {
      acc[12] += w;
      acc[13] += w * w;
    }
  }
  for (int k = 0; k < SLAB_TALLIES; ++k) tallies[id * SLAB_TALLIES + k] = acc[k];
}
