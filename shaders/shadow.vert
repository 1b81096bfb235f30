#version 450 core
// Depth only: the shadow casters seen from the key light, and the depth pre-pass of the
// camera view.

layout(location = 0) in vec3 a_position;

uniform mat4 u_light_view_proj;  // world → key light clip space (or camera clip space)

invariant gl_Position;  // matches mesh.vert in the depth pre-pass

void main() { gl_Position = u_light_view_proj * vec4(a_position, 1.0); }
