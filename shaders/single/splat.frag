#version 450 core
// Adds one sample's share of equation 3 to the pixel: factor times the integral of its Gaussian
// w exp(-|x - b|^2 / (2 s^2)) along the view ray over the part of the ball inside the medium, in
// closed form with erf. The paper clips only at the first surface; with clip_back the ray's
// medium is [first, second surface] and [third, fourth] (depth peeling), so that a Gaussian
// behind the second surface adds nothing to the gap and one behind a thin part (an ear in
// front of the head) still adds its share. From an eye inside the object: [eye, first] and
// [second, third] (clip_back 0: everything ahead of the eye).
flat in vec3 center;  // the ball's (the Gaussian moved by tr_gradient's model)
flat in vec3 own_center, own_slope;  // the sample's own centre p and the model's slope there
flat in float own_depth;  // the model's depth at p less at the anchor (the factor's point)
flat in vec3 gauss_sigma;  // per axis
flat in float cutoff;
flat in vec3 factor;
flat in vec4 clip_plane;  // the piece's side: n . x <= d (zeros: everywhere)
flat in vec4 depth_cut;   // where the linear transmittance model's optical depth is >= 0: likewise
flat in vec4 quad_slope;  // the quadratic model's about own_center, (g, tau_p) ...
flat in vec4 quad_curv;   // ... and (curv, 0): integrated only where it is >= 0 (zeros: no cut,
                          // written only where an axis is concave)
flat in int sample_index;

// per_ray_phase (exact_tr): factor holds the phase at the sample's centre; the fragment takes
// instead each light's share (without its phase) times the phase of this view ray, which a
// peaked phase (|g| near 1) needs: its forward peak is narrower than a Gaussian seen from the eye.
const int MAX_LIGHTS = 16;
layout(std430, binding = 10) readonly buffer LightFactors { vec4 light_factor[]; };
uniform int per_ray_phase;
uniform float g;
uniform int light_count;
uniform int light_type[MAX_LIGHTS];  // 0 point, 1 directional, 2 spot
uniform vec3 light_position[MAX_LIGHTS];
uniform vec3 light_direction[MAX_LIGHTS];

uniform sampler2D front;  // distance from the eye to the first surface (0 where none)
uniform sampler2D back;   // ... to the second surface
uniform sampler2D third;  // ... to the third (0 where none)
uniform sampler2D fourth; // ... to the fourth
uniform int clip_back;
uniform int eye_inside;  // the eye is inside the object: the first surface is where rays leave
uniform vec3 eye, forward, right, up;  // right and up scaled by tan(fov / 2) (and aspect)
uniform vec2 size;  // the image's (the depth textures')
uniform int stride;  // this target's pixel (i, j) is the image's (stride i, stride j)

layout(location = 0) out vec4 radiance;

// Abramowitz and Stegun 7.1.26, |error| < 1.5e-7.
float erf_approx(float x) {
  float s = sign(x), a = abs(x);
  float t = 1.0 / (1.0 + 0.3275911 * a);
  float y = 1.0 - ((((1.061405429 * t - 1.453152027) * t + 1.421413741) * t - 0.284496736) * t + 0.254829592) * t * exp(-a * a);
  return s * y;
}

// erfc(x) exp(x^2) for x >= 0: A&S 7.1.26's own factor below 2, a continued fraction above
// (relative error < 5e-5 both), where the former's would be 4 % at 10.
float erfcx(float x) {
  if (x < 2.0) {
    float t = 1.0 / (1.0 + 0.3275911 * x);
    return ((((1.061405429 * t - 1.453152027) * t + 1.421413741) * t - 0.284496736) * t + 0.254829592) * t;
  }
  float f = x + 3.0 / x;
  f = x + 2.5 / f;
  f = x + 2.0 / f;
  f = x + 1.5 / f;
  f = x + 1.0 / f;
  f = x + 0.5 / f;
  return 0.56418958 / f;
}

// Along the ray eye + t d, with s = t - tp (tp: the point nearest own_center), the log of the
// Gaussian times the model's transmittance is E(s) = -(ea s^2 + eb s + ec), a parabola whose
// vertex is where the moved Gaussian peaks. Set per fragment by main().
float ea, eb, ec, ek, es;  // ek = sqrt(ea), es = the vertex

float expo(float s) { return -((ea * s + eb) * s + ec); }

// The integral of exp(E) over [s1, s2] times 2 ek / sqrt(pi), without leaving float's range or
// its precision. With z = ek (s - es) it is exp(E(es)) (erf(z2) - erf(z1)); where both ends lie on
// one side of the vertex, erfc differences whose exp(-z^2) is exp(E) at the ends, evaluated
// directly. A dense medium moves the Gaussian far outside (a vertex 500 units away, E(es) near
// 8e5): its tail on the segment is then a difference of two erf within 1e-7 of one (A&S's error,
// and float's spacing there) times that scale, and E(es) itself is a difference of two such
// numbers, which float does not hold (the stress suite's mixed/1621, a third of a pixel's single
// term; mixed/1775, 4x its bound).
float erf_span(float s1, float s2) {
  float z1 = ek * (s1 - es), z2 = ek * (s2 - es);
  // The vertex on the segment: erf differences (its peak E(es) is then a small number).
  if (z1 < 0.0 && z2 > 0.0) return exp(ea * es * es - ec) * (erf_approx(z2) - erf_approx(z1));
  if (z1 >= 0.0) return exp(expo(s1)) * erfcx(z1) - exp(expo(s2)) * erfcx(z2);
  return exp(expo(s2)) * erfcx(-z2) - exp(expo(s1)) * erfcx(-z1);
}

// Henyey-Greenstein at cosine c (as shaders/single/shade.comp).
float hg(float c) {
  float d = 1.0 + g * g - 2.0 * g * c;
  return (1.0 - g * g) / (4.0 * 3.14159265 * d * sqrt(d));
}

// The factor for view ray d: each light's share times the phase between d and the light.
vec3 ray_factor(vec3 d) {
  if (per_ray_phase == 0) return factor;
  vec3 sum = vec3(0.0);
  for (int l = 0; l < light_count; ++l) {
    vec3 wl = light_type[l] == 1 ? -light_direction[l] : normalize(light_position[l] - own_center);
    sum += light_factor[sample_index * light_count + l].rgb * hg(dot(wl, d));
  }
  return sum;
}

// Clips the chord [x, y] of the ray eye + t d to the plane's side n . x <= w (empty: y <= x).
void clip_chord(vec4 plane, vec3 d, inout float x, inout float y) {
  float nd = dot(plane.xyz, d), ne = plane.w - dot(plane.xyz, eye);
  if (nd > 0.0) y = min(y, ne / nd);
  else if (nd < 0.0) x = max(x, ne / nd);
  else if (ne < 0.0) y = x;
}

const float OPEN = 1e30;  // an interval's open end
const vec2 EVERYWHERE = vec2(-OPEN, OPEN), NOWHERE = vec2(OPEN, -OPEN);

// Where along the ray the quadratic model's optical depth, tau_p + g . e + 1/2 sum_k curv_k e_k^2
// with e = o + s d the offset from own_center (s = t - tp), is >= 0: up to two intervals of s,
// keep0 and keep1 (empty: y <= x). In s it is a s^2 + b s + c; over a chord
// of half length hc where the s^2 term is negligible, a half-line.
void quad_keep(vec3 d, vec3 o, float hc, out vec2 keep0, out vec2 keep1) {
  vec3 cv = quad_curv.xyz;
  float a = 0.5 * dot(cv, d * d);
  float b = dot(quad_slope.xyz, d) + dot(cv, o * d);
  float c = quad_slope.w + dot(quad_slope.xyz, o) + 0.5 * dot(cv, o * o);
  keep0 = EVERYWHERE;
  keep1 = NOWHERE;
  if (abs(a) * hc * hc <= 1e-6 * (abs(b) * hc + abs(c))) {
    if (b > 0.0) keep0.x = -c / b;
    else if (b < 0.0) keep0.y = -c / b;
    else if (c < 0.0) keep0 = NOWHERE;
    return;
  }
  float disc = b * b - 4.0 * a * c;
  if (disc <= 0.0) {
    // No real zero: negative everywhere (a < 0) or nowhere.
    if (a < 0.0) keep0 = NOWHERE;
    return;
  }
  // The stable pair of roots (no cancellation between b and the square root).
  float q = -0.5 * (b + (b >= 0.0 ? sqrt(disc) : -sqrt(disc)));
  float r1 = q / a, r2 = c / q;
  vec2 r = vec2(min(r1, r2), max(r1, r2));
  if (a < 0.0) {
    keep0 = r;  // >= 0 between the zeros
  } else {
    keep0.y = r.x;  // and outside them
    keep1 = vec2(r.y, OPEN);
  }
}

// The span of [u, w] (in t) inside the quadratic model's keep intervals (in t: s + tp).
float kept_span(float u, float w, vec2 keep0, vec2 keep1, float tp) {
  float sum = 0.0;
  float x0 = max(u, keep0.x), y0 = min(w, keep0.y);
  if (y0 > x0) sum += erf_span(x0 - tp, y0 - tp);
#ifdef QUAD_CUT
  float x1 = max(u, keep1.x), y1 = min(w, keep1.y);
  if (y1 > x1) sum += erf_span(x1 - tp, y1 - tp);
#endif
  return sum;
}

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy) * stride;
  if (px.x >= int(size.x) || px.y >= int(size.y)) discard;
  float ta = texelFetch(front, px, 0).r;
  if (ta <= 0.0) discard;
  vec2 s = (vec2(px) + 0.5) / size * 2.0 - 1.0;
  vec3 d = normalize(forward + right * s.x + up * s.y);
  vec3 to = center - eye;
  float tm = dot(to, d);  // the ball's chord is about its centre's closest point
  float h2 = max(dot(to, to) - tm * tm, 0.0);
  float r2 = cutoff * cutoff;
  if (h2 >= r2) discard;
  float half_chord = sqrt(r2 - h2);
  float x = tm - half_chord, y = tm + half_chord;
  // Along the ray, from the point nearest own_center p (small numbers, whose differences keep
  // float's precision), u(s) = o + s d = x - p: the exponent sum_k u_k^2 / (2 s_k^2) + slope . u +
  // own_depth is ea s^2 + eb s + ec.
  vec3 prec = 1.0 / (gauss_sigma * gauss_sigma);
  float tp = dot(own_center - eye, d);
  vec3 o = eye + tp * d - own_center;
  ea = 0.5 * dot(prec, d * d);
  eb = dot(prec, o * d) + dot(own_slope, d);
  ec = 0.5 * dot(prec, o * o) + dot(own_slope, o) + own_depth;
  ek = sqrt(ea);
  es = -0.5 * eb / ea;
  // erf of the chord's ends relative to the peak, per interval of the medium.
  // A piece's plane clips the chord to its side, the depth cut to where the model holds.
  clip_chord(clip_plane, d, x, y);
  clip_chord(depth_cut, d, x, y);
  if (y <= x) discard;
  // The quadratic model (tr_hessian) clips further where its curvature is concave: its depth
  // falls away from the centre, negative on the near side of the linear cut too.
  // Only in the variant built with QUAD_CUT (tr_gradient and tr_hessian: SinglePipeline::render);
  // without it the work is not there at all (a CPU rasteriser runs both sides of a branch).
  vec2 keep0 = EVERYWHERE, keep1 = NOWHERE;
#ifdef QUAD_CUT
  if (any(lessThan(quad_curv.xyz, vec3(0.0)))) {
    quad_keep(d, o, half_chord + abs(tm - tp), keep0, keep1);  // s reaches that far from tp
    keep0 += tp;
    keep1 += tp;
  }
#endif
  // The medium along the ray: from outside [1st, 2nd] and [3rd, 4th surface]; from an eye inside
  // the object [eye, 1st] and [2nd, 3rd]; an interval with no surface to end it stays open.
  float lo = max(x, eye_inside != 0 ? 0.0 : ta), hi = y, span = 0.0;
  float lo2 = OPEN, hi2 = -OPEN;  // the second interval (none)
  if (clip_back != 0) {
    float tb = texelFetch(back, px, 0).r;
    float t3 = texelFetch(third, px, 0).r;
    if (eye_inside != 0) {
      hi = min(hi, ta);
      if (tb > ta) {
        lo2 = max(x, tb);
        hi2 = t3 > tb ? min(y, t3) : y;
      }
    } else {
      if (tb > ta) hi = min(hi, tb);
      if (t3 > tb && tb > ta) {
        float t4 = texelFetch(fourth, px, 0).r;
        lo2 = max(x, t3);
        hi2 = t4 > t3 ? min(y, t4) : y;
      }
    }
  }
  if (hi2 > lo2) span += kept_span(lo2, hi2, keep0, keep1, tp);
  if (hi > lo) span += kept_span(lo, hi, keep0, keep1, tp);
  if (span <= 0.0) discard;
  float integral = 0.88622693 / ek * span;
  radiance = vec4(ray_factor(d) * integral, 0.0);
}
