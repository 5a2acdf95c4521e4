#version 450 core
// Adds one sample's share of equation 3 to the pixel: factor times the integral of its Gaussian
// w exp(-|x - b|^2 / (2 s^2)) along the view ray over the part of the ball inside the medium, in
// closed form with erf. The paper clips only at the first surface; with clip_back the ray's
// medium is [first, second surface] and [third, fourth] (depth peeling), so that a Gaussian
// behind the second surface adds nothing to the gap and one behind a thin part (an ear in
// front of the head) still adds its share.
flat in vec3 center;
flat in vec3 gauss_sigma;  // per axis
flat in float cutoff;
flat in vec3 factor;
flat in vec4 clip_plane;  // the piece's side: n . x <= d (zeros: everywhere)

uniform sampler2D front;  // distance from the eye to the first surface (0 where none)
uniform sampler2D back;   // ... to the second surface
uniform sampler2D third;  // ... to the third (0 where none)
uniform sampler2D fourth; // ... to the fourth
uniform int clip_back;
uniform vec3 eye, forward, right, up;  // right and up scaled by tan(fov / 2) (and aspect)
uniform vec2 size;

layout(location = 0) out vec4 radiance;

// Abramowitz and Stegun 7.1.26, |error| < 1.5e-7.
float erf_approx(float x) {
  float s = sign(x), a = abs(x);
  float t = 1.0 / (1.0 + 0.3275911 * a);
  float y = 1.0 - ((((1.061405429 * t - 1.453152027) * t + 1.421413741) * t - 0.284496736) * t + 0.254829592) * t * exp(-a * a);
  return s * y;
}

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  float ta = texelFetch(front, px, 0).r;
  if (ta <= 0.0) discard;
  vec2 s = gl_FragCoord.xy / size * 2.0 - 1.0;
  vec3 d = normalize(forward + right * s.x + up * s.y);
  // Along the ray x(t) = eye + t d the exponent sum_k (x_k - c_k)^2 / (2 s_k^2) is
  // (A t^2 + 2 B t + C) / 2: a Gaussian in t centred at -B / A.
  vec3 prec = 1.0 / (gauss_sigma * gauss_sigma);
  vec3 o = eye - center;
  float A = dot(prec, d * d), B = dot(prec, o * d), C = dot(prec, o * o);
  float tc = -B / A;
  float q = max(C - B * B / A, 0.0);  // twice the exponent at the peak
  vec3 to = center - eye;
  float tm = dot(to, d);  // the ball's chord is about the centre's closest point
  float h2 = max(dot(to, to) - tm * tm, 0.0);
  float r2 = cutoff * cutoff;
  if (h2 >= r2) discard;
  float half_chord = sqrt(r2 - h2);
  float x = tm - half_chord, y = tm + half_chord;
  float k = sqrt(0.5 * A);
  // erf of the chord's ends relative to the peak, per interval of the medium.
  // A piece's plane clips the chord to its side: eye + t d with n . (eye + t d) <= w.
  float nd = dot(clip_plane.xyz, d), ne = clip_plane.w - dot(clip_plane.xyz, eye);
  if (nd > 0.0) y = min(y, ne / nd);
  else if (nd < 0.0) x = max(x, ne / nd);
  else if (ne < 0.0) discard;
  float lo = max(x, ta), hi = y, span = 0.0;
  if (clip_back != 0) {
    float tb = texelFetch(back, px, 0).r;
    if (tb > ta) hi = min(hi, tb);
    float t3 = texelFetch(third, px, 0).r;
    if (t3 > tb && tb > ta) {
      float t4 = texelFetch(fourth, px, 0).r;
      float hi2 = t4 > t3 ? min(y, t4) : y;
      float lo2 = max(x, t3);
      if (hi2 > lo2) span += erf_approx((hi2 - tc) * k) - erf_approx((lo2 - tc) * k);
    }
  }
  if (hi > lo) span += erf_approx((hi - tc) * k) - erf_approx((lo - tc) * k);
  if (span <= 0.0) discard;
  float integral = exp(-0.5 * q) * 0.88622693 / k * span;
  radiance = vec4(factor * integral, 0.0);
}
