#version 450 core
// Smooth-shaded body or cloth with per-triangle colours, key + fill light, soft shadows.
// Cloth is lit on both sides: a back face (seen from inside) flips its normal and takes
// u_back_colour.

#include "lighting.glsl"

// One sRGB colour per triangle of the current draw, indexed by gl_PrimitiveID.
layout(std430, binding = 0) readonly buffer FaceColours { vec4 face_colours[]; };

uniform bool u_two_sided;
uniform vec3 u_back_colour;  // sRGB
uniform vec3 u_eye;          // camera position (world)
uniform float u_specular;    // strength of the key light's highlight
uniform float u_shininess;   // Blinn-Phong exponent

in vec3 v_world_pos;
in vec3 v_normal;
out vec4 frag_colour;

void main() {
  vec3 n = normalize(v_normal);
  vec3 base = face_colours[gl_PrimitiveID].rgb;
  if (!gl_FrontFacing) {
    n = -n;
    if (u_two_sided) base = u_back_colour;
  }
  vec3 to_eye = normalize(u_eye - v_world_pos);
  // Smooth normals can face away from the viewer near silhouettes; bend them back so the
  // lighting does not flip there.
  if (dot(n, to_eye) < 0.0) n = normalize(n - 1.01 * dot(n, to_eye) * to_eye);

  float visibility = key_visibility(v_world_pos, n);
  vec3 colour = srgb_to_linear(base) * diffuse_light(n, visibility);
  vec3 half_dir = normalize(u_key_dir + to_eye);
  colour += u_specular * u_key_colour * visibility *
            pow(max(dot(n, half_dir), 0.0), u_shininess) * step(0.0, dot(n, u_key_dir));
  frag_colour = vec4(linear_to_srgb(colour), 1.0);
}
