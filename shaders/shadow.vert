#version 450 core
// Depth of the shadow casters as seen from the key light.

layout(location = 0) in vec3 a_position;

uniform mat4 u_light_view_proj;  // world → key light clip space

void main() { gl_Position = u_light_view_proj * vec4(a_position, 1.0); }
