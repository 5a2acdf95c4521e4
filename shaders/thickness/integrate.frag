#version 450 core
// Single scattering in a homogeneous medium between the first surface A and the second B along
// each view ray (depth peeling; from an eye inside the object, between the eye and the first), lit through the shadow maps. The segment is cut into `steps`
// pieces; the light's path length inside the medium |Cc| is read from the light's shadow map at
// the pieces' ends C, and over each piece [0, h] the transmittance along both paths,
// exp(-sigma_t (u + |Cc|(u))), is integrated exactly for |Cc| linear between its ends:
//   L = sum_k sigma_s p(theta) E exp(-sigma_t t_k) h mean(exp(-sigma_t (u + |Cc|(u))))
// (a midpoint value of the light's transmittance misses its curvature over sigma_t h: 30% of the
// light of a medium 10 mean free paths per piece).
// Refraction at the boundary is neglected, as in the blog post this follows.
const int MAX_LIGHTS = 16;
const float PI = 3.14159265358979;

uniform sampler2D front;  // distance from the eye to the first surface (0 where none)
uniform sampler2D back;   // ... to the second surface
uniform int eye_inside;   // the eye is inside the object: the medium is [eye, first surface]
uniform sampler2D shadow_maps[MAX_LIGHTS];
uniform mat4 light_matrix[MAX_LIGHTS];  // world -> light clip space
uniform int light_count;
uniform int light_type[MAX_LIGHTS];     // 0 point, 1 directional, 2 spot
uniform vec3 light_position[MAX_LIGHTS];  // directional: the shadow map's origin plane point
uniform vec3 light_direction[MAX_LIGHTS];
uniform vec3 light_power[MAX_LIGHTS];
uniform vec2 light_cone[MAX_LIGHTS];
uniform vec3 eye, forward, right, up;   // right and up scaled by tan(fov / 2) (and aspect)
uniform vec2 size;
uniform vec3 sigma_s;
uniform vec3 sigma_t;
uniform float g;
uniform int steps;

layout(location = 0) out vec4 radiance;

float hg(float c) {
  float d = 1.0 + g * g - 2.0 * g * c;
  return (1.0 - g * g) / (4.0 * PI * d * sqrt(d));
}

// The mean of exp(-f) over an interval on which f rises linearly from a to b:
// (exp(-a) - exp(-b)) / (b - a), for either order and without overflow.
vec3 exp_mean(vec3 a, vec3 b) {
  vec3 x = abs(b - a);
  vec3 series = 1.0 - x * (0.5 - x / 6.0);
  return exp(-min(a, b)) * mix(series, (1.0 - exp(-x)) / max(x, vec3(1e-30)), greaterThan(x, vec3(1e-2)));
}

// The distance light i's map holds at uv: the nearest texel's, at the point itself rather than
// at the texel's centre (the texel keeps its surface's slope per texel, shaders/common/
// distance.frag). Exact on a flat face seen from a directional light, to second order in the
// texel otherwise (docs/pipelines/thickness.md).
float map_distance(int i, vec2 uv) {
  ivec2 n = textureSize(shadow_maps[i], 0);
  vec2 p = uv * vec2(n) - 0.5;  // in texels, centres at whole numbers
  ivec2 t = clamp(ivec2(floor(p + 0.5)), ivec2(0), n - 1);
  vec3 s = texelFetch(shadow_maps[i], t, 0).rgb;
  vec2 o = p - vec2(t);
  return s.r + s.g * o.x + s.b * o.y;
}

// Light i's irradiance at c scattered into -d, before attenuation; *inside: its path length in the
// medium before c, from the shadow map.
vec3 light_at(int i, vec3 c, vec3 d, out float inside) {
  vec3 e = light_power[i], wl;
  float dc;  // distance of C from the light's origin, as the shadow map measures it
  if (light_type[i] == 1) {
    wl = -light_direction[i];
    dc = dot(c - light_position[i], light_direction[i]);
  } else {
    vec3 to = light_position[i] - c;
    dc = length(to);
    wl = to / dc;
    e /= dc * dc;
    if (light_type[i] == 2) {
      float cs = dot(-wl, light_direction[i]);
      e *= light_cone[i].y > light_cone[i].x ? smoothstep(light_cone[i].x, light_cone[i].y, cs)
                                             : step(light_cone[i].x, cs);
    }
  }
  vec4 clip = light_matrix[i] * vec4(c, 1.0);
  inside = max(dc - map_distance(i, clip.xy / clip.w * 0.5 + 0.5), 0.0);
  return e * hg(dot(wl, d));
}

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  float ta = texelFetch(front, px, 0).r, tb = texelFetch(back, px, 0).r;
  // From an eye inside the object the ray starts in the medium and leaves it at the first surface.
  if (eye_inside != 0 && ta > 0.0) {
    tb = ta;
    ta = 0.0;
  }
  if (tb <= 0.0 || tb <= ta) {
    radiance = vec4(0.0);
    return;
  }
  // The pixel's ray through its centre; GL's row 0 is the bottom, as is `up` positive.
  vec2 s = gl_FragCoord.xy / size * 2.0 - 1.0;
  vec3 d = normalize(forward + right * s.x + up * s.y);
  float h = (tb - ta) / float(steps);
  vec3 seg_tr = exp(-sigma_t * h);
  vec3 tr = vec3(1.0), sum = vec3(0.0);
  vec3 e0[MAX_LIGHTS];
  float in0[MAX_LIGHTS];
  for (int i = 0; i < light_count; ++i) e0[i] = light_at(i, eye + d * ta, d, in0[i]);
  for (int k = 0; k < steps; ++k) {
    vec3 in_scatter = vec3(0.0);
    for (int i = 0; i < light_count; ++i) {
      float in1;
      vec3 e1 = light_at(i, eye + d * (ta + float(k + 1) * h), d, in1);
      in_scatter += 0.5 * (e0[i] + e1) * exp_mean(sigma_t * in0[i], sigma_t * (in1 + h));
      e0[i] = e1;
      in0[i] = in1;
    }
    sum += tr * h * sigma_s * in_scatter;
    tr *= seg_tr;
  }
  radiance = vec4(sum, 1.0);
}
