// Fresnel reflectance at a dielectric boundary. Part of the kernels' shared library
// (pipelines/common/cl_library.hpp).

// ---- Fresnel for unpolarised light; eta = n_incident / n_transmitted ------------------------

// Reflectance at an interface for incidence cosine cos_i > 0; 1 for total internal reflection.
float fresnel(float cos_i, float eta, float* cos_t) {
  float sin2_t = eta * eta * fmax(0.0f, 1.0f - cos_i * cos_i);
  if (sin2_t >= 1.0f) {
    *cos_t = 0.0f;
    return 1.0f;
  }
  float ct = sqrt(1.0f - sin2_t);
  *cos_t = ct;
  float rs = (eta * cos_i - ct) / (eta * cos_i + ct);
  float rp = (cos_i - eta * ct) / (cos_i + eta * ct);
  return 0.5f * (rs * rs + rp * rp);
}
