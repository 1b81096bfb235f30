#version 450 core
// Wireframe edges: each edge arrives as two vertices with the edge's colour.

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_colour;  // sRGB

uniform mat4 u_view_proj;

out vec3 g_colour;

void main() {
  g_colour = a_colour;
  gl_Position = u_view_proj * vec4(a_position, 1.0);
}
