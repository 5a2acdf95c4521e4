#version 450 core
// Energy-normalised Blinn-Phong under point, directional and spot lights; with `shadowed` set,
// a light counts only where its distance map (shaders/common/distance.frag, seen from the
// light) holds no surface nearer to it than this one, less a bias.
// Radiance = sum over lights of (kd / pi + ks (n + 8) / (8 pi) cos^n(theta_h)) E cos(theta_i),
// with E = intensity / r^2 for point and spot lights and E = irradiance for directional ones.
const int MAX_LIGHTS = 16;
const int POINT = 0;
const int DIRECTIONAL = 1;
const int SPOT = 2;
const float PI = 3.14159265358979;

in vec3 world_position;
in vec3 world_normal;

uniform int light_count;
uniform int light_type[MAX_LIGHTS];
uniform vec3 light_position[MAX_LIGHTS];
uniform vec3 light_direction[MAX_LIGHTS];  // the way the light travels
uniform vec3 light_power[MAX_LIGHTS];      // colour times intensity (or irradiance)
uniform vec2 light_cone[MAX_LIGHTS];       // spot: cos(outer), cos(inner)
uniform vec3 eye;
uniform vec3 kd;
uniform vec3 ks;
uniform float shininess;
uniform int shadowed;
uniform sampler2D shadow_maps[MAX_LIGHTS];
uniform mat4 light_matrix[MAX_LIGHTS];      // the map's projection x view
uniform vec3 shadow_origin[MAX_LIGHTS];     // where the map's distances are measured from
uniform int shadow_along[MAX_LIGHTS];       // 1: along light_direction (directional lights)
uniform float shadow_bias;

// 1 when light i reaches p, else 0.
float lit(int i, vec3 p) {
  vec4 c = light_matrix[i] * vec4(p, 1.0);
  vec2 uv = c.xy / c.w * 0.5 + 0.5;
  if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;
  vec3 d = p - shadow_origin[i];
  float t = shadow_along[i] != 0 ? dot(d, light_direction[i]) : length(d);
  return t <= texture(shadow_maps[i], uv).r + shadow_bias ? 1.0 : 0.0;
}

layout(location = 0) out vec4 radiance;

void main() {
  vec3 n = normalize(world_normal);
  vec3 v = normalize(eye - world_position);
  if (dot(n, v) < 0.0) n = -n;  // seen from inside (camera within the mesh)
  vec3 sum = vec3(0.0);
  for (int i = 0; i < light_count; ++i) {
    vec3 l;
    vec3 e = light_power[i];
    if (light_type[i] == DIRECTIONAL) {
      l = -light_direction[i];
    } else {
      vec3 d = light_position[i] - world_position;
      float r2 = max(dot(d, d), 1e-12);
      l = d * inversesqrt(r2);
      e /= r2;
      if (light_type[i] == SPOT) {
        float c = dot(-l, light_direction[i]);  // smoothstep is undefined for equal edges
        e *= light_cone[i].y > light_cone[i].x ? smoothstep(light_cone[i].x, light_cone[i].y, c)
                                               : step(light_cone[i].x, c);
      }
    }
    float cos_i = dot(n, l);
    if (cos_i <= 0.0) continue;
    if (shadowed != 0 && lit(i, world_position) == 0.0) continue;
    vec3 h = normalize(l + v);
    float spec = (shininess + 8.0) / (8.0 * PI) * pow(max(dot(n, h), 0.0), shininess);
    sum += (kd / PI + ks * spec) * e * cos_i;
  }
  radiance = vec4(sum, 1.0);
}
