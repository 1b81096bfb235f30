#version 450 core
// The floor: a disc under the scene that receives the key light's shadow and fades into the
// background colour toward its rim, so it has no visible edge.

#include "lighting.glsl"

uniform vec3 u_ground_colour;  // sRGB
uniform vec3 u_background;     // sRGB
uniform vec3 u_ground_centre;  // world, on the floor
uniform float u_ground_radius; // metres; fully background beyond it

in vec3 v_world_pos;
in vec3 v_normal;
out vec4 frag_colour;

void main() {
  vec3 n = vec3(0.0, 1.0, 0.0);
  float visibility = key_visibility(v_world_pos, n);
  // Normalise so a fully lit floor shows exactly u_ground_colour; shadow darkens it.
  vec3 lit = diffuse_light(n, 1.0);
  vec3 light = diffuse_light(n, visibility) / max(max(lit.r, lit.g), lit.b);
  vec3 colour = linear_to_srgb(srgb_to_linear(u_ground_colour) * light);
  float r = distance(v_world_pos.xz, u_ground_centre.xz) / u_ground_radius;
  frag_colour = vec4(mix(colour, u_background, smoothstep(0.45, 1.0, r)), 1.0);
}
