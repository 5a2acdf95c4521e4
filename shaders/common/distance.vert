#version 450 core
// Transforms the mesh for a view (the camera or a light) and passes the world position on.
layout(location = 0) in vec3 position;

uniform mat4 view;
uniform mat4 projection;

out vec3 world_position;

void main() {
  world_position = position;
  gl_Position = projection * view * vec4(position, 1.0);
}
