#version 450 core
// The single term at the image's size from a splat that evaluated every stride-th pixel of it
// (splat_scale): those pixels are copied, the others interpolated. Along a view ray through a
// thin part of the medium (the rim) the term grows with the ray's chord through the medium, so the
// interpolation is of the splat's ratio to a guide, 1 - exp(-sigma_t L), L the chord of the ray's
// two intervals ([1st, 2nd] and [3rd, 4th surface]), times this pixel's own guide: bilinear over
// the four nearest evaluated pixels, weighted down where their surfaces lie far from this
// pixel's (an edge in depth: the bunny's ear before its head).
uniform sampler2D low;  // the evaluated pixels: this pixel's (stride i, stride j) is its (i, j)
uniform sampler2D front, back, third, fourth;  // distances to the surfaces (0 where none)
uniform int stride;
uniform int clip_back;      // 0: the splat clipped at the first surface only (guide 1)
uniform int eye_inside;     // the eye is inside the object (the splat's intervals, splat.frag)
uniform float sigma_t;      // the guide's extinction (the medium's median)
uniform float depth_scale;  // a neighbour's weight falls as exp(-(depth difference / this)^2)
// phase_guide (the splat's phase per view ray): the guide is also the lights' phase along each
// pixel's ray, so that a peaked phase (g 0.9: three times brighter 6 degrees nearer its peak) is
// not interpolated from pixels nearer the peak than this one. Each light counts with its power
// (over the squared distance to the ray's first surface for a point or spot light), from the
// middle of the first interval's medium, its shadow unknown here: a guide, divided out again.
const int MAX_LIGHTS = 16;
uniform int phase_guide;
uniform float g;
uniform int light_count;
uniform int light_type[MAX_LIGHTS];  // 0 point, 1 directional, 2 spot
uniform vec3 light_position[MAX_LIGHTS];
uniform vec3 light_direction[MAX_LIGHTS];
uniform vec3 light_power[MAX_LIGHTS];
uniform vec3 eye, forward, right, up;  // right and up scaled by tan(fov / 2) (and aspect)
uniform vec2 size;

layout(location = 0) out vec4 radiance;

// The chord of both intervals (the second only where a surface lies behind the one that ends the
// first): from outside [1st, 2nd] and [3rd, 4th], from an eye inside [eye, 1st] and [2nd, 3rd].
float chord(ivec2 p, out float ta, out float tb) {
  ta = texelFetch(front, p, 0).r;
  tb = texelFetch(back, p, 0).r;
  if (clip_back == 0) return -1.0;  // unbounded: front-only clipping
  float t3 = texelFetch(third, p, 0).r;
  if (eye_inside != 0) {
    float L = ta;
    if (tb > ta) {
      if (t3 <= tb) return -1.0;  // an open mesh
      L += t3 - tb;
    }
    return L;
  }
  if (tb <= ta) return -1.0;  // an open mesh
  float L = tb - ta;
  if (t3 > tb) {
    float t4 = texelFetch(fourth, p, 0).r;
    if (t4 <= t3) return -1.0;
    L += t4 - t3;
  }
  return L;
}

float guide(float L) { return L < 0.0 ? 1.0 : 1.0 - exp(-sigma_t * L); }

// Henyey-Greenstein at cosine c (as shaders/single/splat.frag).
float hg(float c) {
  float d = 1.0 + g * g - 2.0 * g * c;
  return (1.0 - g * g) / (4.0 * 3.14159265 * d * sqrt(d));
}

// The lights' phase along pixel p's ray (1 without phase_guide); ta: its first surface.
float phase(ivec2 p, float ta) {
  if (phase_guide == 0) return 1.0;
  vec2 s = (vec2(p) + 0.5) / size * 2.0 - 1.0;
  vec3 d = normalize(forward + right * s.x + up * s.y);
  vec3 x = eye + d * (eye_inside != 0 ? 0.5 * ta : ta);
  float sum = 0.0;
  for (int l = 0; l < min(light_count, MAX_LIGHTS); ++l) {
    float w = dot(light_power[l], vec3(1.0 / 3.0));
    vec3 wl = -light_direction[l];
    if (light_type[l] != 1) {
      vec3 to = light_position[l] - x;
      float r2 = max(dot(to, to), 1e-20);
      wl = to * inversesqrt(r2);
      w /= r2;
    }
    sum += w * hg(dot(wl, d));
  }
  return sum;
}

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  ivec2 q0 = px / stride;
  ivec2 r = px - q0 * stride;
  if (r == ivec2(0)) {  // evaluated by the splat
    radiance = vec4(texelFetch(low, q0, 0).rgb, 0.0);
    return;
  }
  float ta, tb;
  float L = chord(px, ta, tb);
  // Unbounded here (no second surface found at a silhouette's edge): no ratio to interpolate.
  const bool ratio = L >= 0.0;
  float gd = (ratio ? guide(L) : 1.0) * phase(px, ta);
  if (ta <= 0.0 || !(gd > 0.0)) {
    radiance = vec4(0.0);
    return;
  }
  ivec2 size = textureSize(front, 0);
  vec2 f = vec2(r) / float(stride);
  vec3 sum = vec3(0.0);
  float wsum = 0.0;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      ivec2 c = q0 + ivec2(i, j);
      ivec2 p = c * stride;
      if (p.x >= size.x || p.y >= size.y) continue;
      float la, lb;
      float ll = chord(p, la, lb);
      float lg = ratio ? guide(ll) : 1.0;
      if (la <= 0.0 || lg <= 1e-6) continue;
      lg *= phase(p, la);
      if (!(lg > 0.0)) continue;
      float w = (i == 0 ? 1.0 - f.x : f.x) * (j == 0 ? 1.0 - f.y : f.y);
      float dz = (la - ta) / depth_scale, db = (lb - tb) / depth_scale;
      w *= exp(-dz * dz - db * db) + 1e-6;
      sum += w * texelFetch(low, c, 0).rgb / lg;
      wsum += w;
    }
  radiance = vec4(wsum > 0.0 ? gd * sum / wsum : vec3(0.0), 0.0);
}
