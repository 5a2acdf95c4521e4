// The stratified sampler of rng.cl for tests (tests/unit/pipelines/reference/sampler_test.cpp):
// work item (index, batch, pixel) writes its sample's first three draws, a 1D then a 2D, as
// path.cl takes them: out[3 * ((pixel * batches + batch) * count + index) + 0..2].

__kernel void sampler_draws(int count, int batches, uint seed, __global float* out) {
  int index = get_global_id(0), batch = get_global_id(1), pixel = get_global_id(2);
  Sampler s = sampler_start((uint)pixel, (uint)index, mix32(seed ^ mix32((uint)batch)));
  float u = sampler_1d(&s);
  float2 v = sampler_2d(&s);
  size_t i = 3 * (((size_t)pixel * batches + batch) * count + index);
  out[i] = u;
  out[i + 1] = v.x;
  out[i + 2] = v.y;
}
