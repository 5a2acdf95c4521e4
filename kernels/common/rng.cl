// Random numbers. Part of the OpenCL library the pipelines' kernels share (kernels/common/),
// which the host puts before each program's own files in the order of with_cl_library()
// (pipelines/common/cl_library.hpp): each file after the files whose names it uses.

// ---- Random numbers: PCG32, one stream per (pixel, sample, pass, seed) -------------------------

// `next`, when >= 0, is the uniform the next draw returns (rng_offer: a stratified sample for a
// draw the stream would otherwise make).
typedef struct {
  ulong state;
  float next;
} Rng;

uint pcg_next(Rng* r) {
  ulong old = r->state;
  r->state = old * 6364136223846793005UL + 1442695040888963407UL;
  uint xorshifted = (uint)(((old >> 18u) ^ old) >> 27u);
  uint rot = (uint)(old >> 59u);
  return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
}

// Uniform in [0, 1).
float rng_uniform(Rng* r) {
  if (r->next >= 0.0f) {
    float u = r->next;
    r->next = -1.0f;
    return u;
  }
  return (pcg_next(r) >> 8) * (1.0f / 16777216.0f);
}

// The next draw returns u (in [0, 1)) instead of the stream's.
void rng_offer(Rng* r, float u) { r->next = u; }

Rng rng_seed(uint a, uint b, uint c) {
  Rng r;
  r.next = -1.0f;
  r.state = ((ulong)a << 32) ^ ((ulong)b * 0x9E3779B97F4A7C15UL) ^ ((ulong)c * 0xBF58476D1CE4E5B9UL);
  for (int i = 0; i < 4; ++i) pcg_next(&r);
  return r;
}

// ---- Stratified samples: padded, Owen-scrambled Sobol ------------------------------------------
//
// Burley 2020, "Practical hash-based Owen scrambling" (as pbrt-v4's PaddedSobolSampler and
// Cycles' Sobol-Burley pattern): each 1D draw takes Sobol's first dimension, each 2D draw its
// first two, at the sample's index shuffled by an Owen scramble of its bits; the coordinates are
// Owen-scrambled too. Shuffle and scrambles are hashed from the pixel, the draw's dimension and
// the batch's seed: a draw is independent of every other dimension's (padding) and stratified
// over the batch's samples, each power-of-two prefix of them a (0, m, 2)-net. Every sample is
// uniformly distributed, so any number of samples gives an unbiased mean; the batches of one
// pixel are independent, which is what the standard error is taken from (kernels/reference/
// path.cl).

uint reverse_bits32(uint x) {
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
  x = ((x >> 8) & 0x00FF00FFu) | ((x & 0x00FF00FFu) << 8);
  return (x >> 16) | (x << 16);
}

// A hash of x in which each output bit depends only on the input bits below it (Burley's
// Laine-Karras permutation): on reversed bits, an Owen scramble. Every step after the seed's
// addition is a bijection of x, so over uniform seeds the output is uniform: each scrambled
// sample is exactly uniformly distributed (a seed-dependent multiplier would not keep that).
uint laine_karras(uint x, uint seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}

// Owen's nested uniform scramble of a base-2 fraction (bit 31 its first digit).
uint owen_scramble(uint x, uint seed) {
  return reverse_bits32(laine_karras(reverse_bits32(x), seed));
}

// Sobol's second dimension at index i, as a 32-bit fraction (its first is the bit reversal).
uint sobol_dim1(uint i) {
  uint r = 0u;
  for (uint v = 1u << 31; i != 0u; i >>= 1, v ^= v >> 1)
    if (i & 1u) r ^= v;
  return r;
}

// Wellons' lowbias32: a well-mixed 32-bit hash.
uint mix32(uint x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

float unit_fraction(uint x) { return (x >> 8) * (1.0f / 16777216.0f); }

// One sample's draws: its index in its batch, the batch's seed, the next dimension.
typedef struct {
  uint pixel, index, seed, dim;
} Sampler;

Sampler sampler_start(uint pixel, uint index, uint seed) {
  Sampler s = {pixel, index, seed, 0u};
  return s;
}

uint sampler_hash(Sampler* s) {
  return mix32(s->pixel ^ mix32(s->dim++ * 0x9E3779B9u ^ mix32(s->seed)));
}

float sampler_1d(Sampler* s) {
  uint h = sampler_hash(s);
  uint i = owen_scramble(s->index, h);
  return unit_fraction(owen_scramble(reverse_bits32(i), mix32(h ^ 0xa511e9b3u)));
}

float2 sampler_2d(Sampler* s) {
  uint h = sampler_hash(s);
  uint i = owen_scramble(s->index, h);
  return (float2)(unit_fraction(owen_scramble(reverse_bits32(i), mix32(h ^ 0xa511e9b3u))),
                  unit_fraction(owen_scramble(sobol_dim1(i), mix32(h ^ 0x63d83595u))));
}
