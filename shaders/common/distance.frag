#version 450 core
// Writes the distance of the nearest surface from the view's origin: along the ray (point lights,
// the camera) or along `direction` (directional lights). With `peel` set, surfaces not farther
// than the first layer (in `first_layer`) are discarded, so the depth test keeps the second layer.
// Green and blue hold the distance's change per texel along x and y on the drawn surface, so a
// reader can take the distance at any point of the texel, not only at its centre (thickness's
// light path length in optically thick media: docs/pipelines/thickness.md); texels no surface
// covers hold 0 there.
in vec3 world_position;

uniform vec3 origin;
uniform vec3 direction;
uniform int along_direction;
uniform int peel;
uniform sampler2D first_layer;

layout(location = 0) out vec4 distance_out;

void main() {
  vec3 d = world_position - origin;
  float t = along_direction != 0 ? dot(d, direction) : length(d);
  if (peel != 0) {
    float first = texelFetch(first_layer, ivec2(gl_FragCoord.xy), 0).r;
    if (t <= first * (1.0 + 1e-4) + 1e-5) discard;
  }
  distance_out = vec4(t, dFdxFine(t), dFdyFine(t), 1.0);
}
