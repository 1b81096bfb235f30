#version 450 core
// Bodies, cloth and the ground: positions are already in world coordinates (metres).

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;  // smooth vertex normal

uniform mat4 u_view_proj;  // world → clip

invariant gl_Position;  // same depth as the pre-pass (shadow.vert)

out vec3 v_world_pos;
out vec3 v_normal;

void main() {
  v_world_pos = a_position;
  v_normal = a_normal;
  gl_Position = u_view_proj * vec4(a_position, 1.0);
}
