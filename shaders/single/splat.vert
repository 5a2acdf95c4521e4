#version 450 core
// One camera-facing quad per sample (instanced, 4 vertices as a strip) that covers the
// projection of the sample's ball (radius 3 sigma). A ball around the eye gets the whole screen.
layout(std430, binding = 0) readonly buffer Positions { float position[]; };
layout(std430, binding = 5) readonly buffer Sigmas { float sigma[]; };
layout(std430, binding = 4) readonly buffer Colors { vec4 color[]; };
// Offset of the Gaussian's centre (exact_tr with tr_gradient: kernels/single/shade.cl) and its
// cut-off radius if above 3 sigma, else zeros.
layout(std430, binding = 6) readonly buffer Shifts { vec4 shift[]; };
// Standard deviation of the Gaussian per axis (tr_gradient's curvature stretches it; else sigma);
// w: the transmittance model's optical depth at the sample's centre less at its anchor (0 without
// tr_gradient).
layout(std430, binding = 7) readonly buffer Axes { vec4 axes[]; };

// A piece split at an extinction jump counts only where n . x <= d (xyz n, w d; zeros: everywhere).
layout(std430, binding = 8) readonly buffer Planes { vec4 plane[]; };
// Where the transmittance model's optical depth is negative (exact_tr with tr_gradient:
// kernels/single/shade.cl), three a sample: cut[3 i], the linear model's, integrate only where
// n . x <= d (zeros: everywhere); cut[3 i + 1] and cut[3 i + 2], the quadratic model's about the
// sample's own centre p, tau_p + g . (x - p) + 1/2 sum_k curv_k (x_k - p_k)^2 as (g, tau_p) and
// (curv, 0), integrate only where it is >= 0 (zeros: everywhere).
layout(std430, binding = 9) readonly buffer Cuts { vec4 cut[]; };

uniform mat4 view_projection;
uniform vec3 eye;
// A splat at 1/stride of the image's size evaluates the image's pixel (stride i, stride j) at its
// pixel (i, j): this moves the quads by the difference of the two centres, in clip space.
uniform vec2 ndc_shift;
// The draw's first sample (the coarse set is drawn as a prefix and the pieces split off it).
uniform int first;

flat out vec3 center;
flat out vec3 own_center;  // the sample's own (unmoved): the frame the fragment integrates in
flat out vec3 own_slope;   // the model's optical depth gradient there
flat out float own_depth;  // and its depth there less at the anchor
flat out vec3 gauss_sigma;
flat out float cutoff;  // radius of the ball the Gaussian is integrated over
flat out vec3 factor;
flat out vec4 clip_plane;
flat out vec4 depth_cut;
flat out vec4 quad_slope;
flat out vec4 quad_curv;
flat out int sample_index;

void main() {
  uint i = uint(first + gl_InstanceID);
  own_center = vec3(position[3u * i], position[3u * i + 1u], position[3u * i + 2u]);
  center = own_center + shift[i].xyz;
  gauss_sigma = axes[i].xyz;
  own_slope = -shift[i].xyz / (gauss_sigma * gauss_sigma);  // the move is -slope sigma^2
  own_depth = axes[i].w;
  factor = color[i].rgb;
  clip_plane = plane[i];
  depth_cut = cut[3u * i];
  quad_slope = cut[3u * i + 1u];
  quad_curv = cut[3u * i + 2u];
  sample_index = int(i);
  vec2 corner = vec2(gl_VertexID & 1, (gl_VertexID >> 1) & 1) * 2.0 - 1.0;
  float radius = max(3.0 * max(gauss_sigma.x, max(gauss_sigma.y, gauss_sigma.z)), shift[i].w);
  cutoff = radius;
  vec3 to = center - eye;
  float dist = length(to);
  if (dist < radius * 1.05 || dot(factor, factor) == 0.0) {
    // Inside (or nearly) the ball: cover the screen; or nothing to add: a degenerate quad.
    gl_Position = dot(factor, factor) == 0.0 ? vec4(0.0, 0.0, 0.0, 1.0) : vec4(corner, 0.0, 1.0);
    return;
  }
  vec3 f = to / dist;
  vec3 ref = abs(f.y) < 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
  vec3 u = normalize(cross(ref, f)), v = cross(f, u);
  // The cone from the eye tangent to the ball meets the plane through the centre at this radius.
  float half_size = radius * dist / sqrt(dist * dist - radius * radius);
  gl_Position = view_projection * vec4(center + (u * corner.x + v * corner.y) * half_size, 1.0);
  gl_Position.xy += ndc_shift * gl_Position.w;
}
