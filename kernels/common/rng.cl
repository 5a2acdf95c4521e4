// Random numbers. Part of the OpenCL library the pipelines' kernels share (kernels/common/),
// which the host puts before each program's own files in the order of with_cl_library()
// (pipelines/common/cl_library.hpp): each file after the files whose names it uses.

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
