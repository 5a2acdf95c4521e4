#version 450 core
// Per frame and per sample, the factor of equation 3 that does not depend on the view ray's
// position within the splat: the Gaussian's weight times
//   sigma_s(b) * psi(b, to eye) * sum_lights E_l(b) * psi(b, to light l) * p(cos theta_l),
// where psi is the transmittance from b to the boundary read from the sample's spherical
// harmonics (of the transmittance, or of the optical depth then exponentiated). Evaluated once
// per sample, so the splatting's fragment work does not grow with the number of lights.
// The basis must equal pipelines/single/sh.cpp.
layout(local_size_x = 64) in;

const int MAX_LIGHTS = 16;
const float PI = 3.14159265358979;

layout(std430, binding = 0) readonly buffer Positions { float position[]; };
layout(std430, binding = 1) readonly buffer Weights { float weight[]; };
layout(std430, binding = 2) readonly buffer SigmaS { float sigma_s[]; };
layout(std430, binding = 3) readonly buffer Sh { float sh[]; };
layout(std430, binding = 4) writeonly buffer Colors { vec4 color[]; };

uniform int count;
uniform int bands;       // coefficients per channel: bands^2
uniform int depth_mode;  // 1: the harmonics hold optical depth
uniform vec3 eye;
uniform float g;
uniform int light_count;
uniform int light_type[MAX_LIGHTS];  // 0 point, 1 directional, 2 spot
uniform vec3 light_position[MAX_LIGHTS];
uniform vec3 light_direction[MAX_LIGHTS];
uniform vec3 light_power[MAX_LIGHTS];
uniform vec2 light_cone[MAX_LIGHTS];  // cos(outer), cos(inner)

const int MAX_BANDS = 8;
const int MAX_COEFFS = MAX_BANDS * MAX_BANDS;

// Real SH without the Condon-Shortley phase, index l^2 + l + m, by the recurrences of
// pipelines/single/sh.cpp (keep them equal): Y_l^0 = K P_l(z), Y_l^{+-m} = sqrt(2) K P~_l^m(z)
// Re / Im((x + iy)^m), with P~_l^m = P_l^m / sin^m(theta).
void basis(vec3 d, out float y[MAX_COEFFS]) {
  float c[MAX_BANDS], sn[MAX_BANDS];
  c[0] = 1.0;
  sn[0] = 0.0;
  for (int m = 1; m < bands; ++m) {
    c[m] = c[m - 1] * d.x - sn[m - 1] * d.y;
    sn[m] = c[m - 1] * d.y + sn[m - 1] * d.x;
  }
  float pmm = 1.0;
  for (int m = 0; m < bands; ++m) {
    if (m > 0) pmm *= float(2 * m - 1);
    float p_prev = 0.0, p = pmm;
    for (int l = m; l < bands; ++l) {
      if (l == m + 1) {
        p_prev = p;
        p = d.z * float(2 * m + 1) * pmm;
      } else if (l > m + 1) {
        float next = (float(2 * l - 1) * d.z * p - float(l + m - 1) * p_prev) / float(l - m);
        p_prev = p;
        p = next;
      }
      float ratio = 1.0;
      for (int k = l - m + 1; k <= l + m; ++k) ratio /= float(k);
      float k_lm = sqrt(float(2 * l + 1) / (4.0 * PI) * ratio);
      if (m == 0) {
        y[l * l + l] = k_lm * p;
      } else {
        y[l * l + l + m] = 1.41421356 * k_lm * p * c[m];
        y[l * l + l - m] = 1.41421356 * k_lm * p * sn[m];
      }
    }
  }
}

// Transmittance per channel of sample i towards the direction whose basis values are y.
vec3 transmittance(uint i, float y[MAX_COEFFS]) {
  int n = bands * bands;
  vec3 s = vec3(0.0);
  for (int c = 0; c < 3; ++c) {
    uint base = (i * 3u + uint(c)) * uint(n);
    float acc = 0.0;
    for (int k = 0; k < n; ++k) acc += sh[base + uint(k)] * y[k];
    s[c] = acc;
  }
  return depth_mode != 0 ? exp(-max(s, vec3(0.0))) : clamp(s, vec3(0.0), vec3(1.0));
}

// As kernels/common/lights.cl: a hard edge when the cone has no soft band.
float smooth_step(float e0, float e1, float x) {
  if (e1 <= e0) return x >= e0 ? 1.0 : 0.0;
  float t = clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

float hg(float c) {
  float d = 1.0 + g * g - 2.0 * g * c;
  return (1.0 - g * g) / (4.0 * PI * d * sqrt(d));
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uint(count)) return;
  vec3 b = vec3(position[3u * i], position[3u * i + 1u], position[3u * i + 2u]);
  vec3 to_eye = normalize(eye - b);
  float y[MAX_COEFFS];
  basis(to_eye, y);
  vec3 view_tr = transmittance(i, y);
  vec3 in_scatter = vec3(0.0);
  for (int l = 0; l < light_count; ++l) {
    vec3 wl, e = light_power[l];
    if (light_type[l] == 1) {
      wl = -light_direction[l];
    } else {
      vec3 to = light_position[l] - b;
      float r2 = max(dot(to, to), 1e-12);
      wl = to * inversesqrt(r2);
      e /= r2;
      if (light_type[l] == 2) e *= smooth_step(light_cone[l].x, light_cone[l].y, dot(-wl, light_direction[l]));
    }
    basis(wl, y);
    // The view ray travels along -to_eye; light arrives travelling along -wl.
    in_scatter += e * transmittance(i, y) * hg(dot(wl, -to_eye));
  }
  vec3 ss = vec3(sigma_s[3u * i], sigma_s[3u * i + 1u], sigma_s[3u * i + 2u]);
  color[i] = vec4(weight[i] * ss * view_tr * in_scatter, 0.0);
}
