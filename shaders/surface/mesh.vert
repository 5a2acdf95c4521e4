#version 450 core
// Transforms the mesh; passes world-space position and normal to the fragment stage.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;

uniform mat4 view;
uniform mat4 projection;

out vec3 world_position;
out vec3 world_normal;

void main() {
  world_position = position;
  world_normal = normal;
  gl_Position = projection * view * vec4(position, 1.0);
}
