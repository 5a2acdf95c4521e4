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

void basis(vec3 d, out float y[25]) {
  float x = d.x, yy = d.y, z = d.z;
  float x2 = x * x, y2 = yy * yy, z2 = z * z;
  y[0] = 0.282094791773878;
  y[1] = 0.488602511902920 * yy;
  y[2] = 0.488602511902920 * z;
  y[3] = 0.488602511902920 * x;
  y[4] = 1.092548430592079 * x * yy;
  y[5] = 1.092548430592079 * yy * z;
  y[6] = 0.315391565252520 * (3.0 * z2 - 1.0);
  y[7] = 1.092548430592079 * x * z;
  y[8] = 0.546274215296040 * (x2 - y2);
  y[9] = 0.590043589926644 * yy * (3.0 * x2 - y2);
  y[10] = 2.890611442640554 * x * yy * z;
  y[11] = 0.457045799464466 * yy * (5.0 * z2 - 1.0);
  y[12] = 0.373176332590115 * z * (5.0 * z2 - 3.0);
  y[13] = 0.457045799464466 * x * (5.0 * z2 - 1.0);
  y[14] = 1.445305721320277 * z * (x2 - y2);
  y[15] = 0.590043589926644 * x * (x2 - 3.0 * y2);
  y[16] = 2.503342941796705 * x * yy * (x2 - y2);
  y[17] = 1.770130769779931 * yy * z * (3.0 * x2 - y2);
  y[18] = 0.946174695757560 * x * yy * (7.0 * z2 - 1.0);
  y[19] = 0.669046543557289 * yy * z * (7.0 * z2 - 3.0);
  y[20] = 0.105785546915204 * (35.0 * z2 * z2 - 30.0 * z2 + 3.0);
  y[21] = 0.669046543557289 * x * z * (7.0 * z2 - 3.0);
  y[22] = 0.473087347878780 * (x2 - y2) * (7.0 * z2 - 1.0);
  y[23] = 1.770130769779931 * x * z * (x2 - 3.0 * y2);
  y[24] = 0.625835735449176 * (x2 * (x2 - 3.0 * y2) - y2 * (3.0 * x2 - y2));
}

// Transmittance per channel of sample i towards the direction whose basis values are y.
vec3 transmittance(uint i, float y[25]) {
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

// As kernels/reference/common.cl: a hard edge when the cone has no soft band.
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
  float y[25];
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
