// Shared lighting for mesh.frag and ground.frag, inserted where they say
// #include "lighting.glsl" (the renderer expands includes before compiling).
// All colours are linear RGB here; inputs in sRGB go through srgb_to_linear first.

uniform vec3 u_key_dir;         // unit vector toward the key light (world)
uniform vec3 u_key_colour;      // key light radiance
uniform vec3 u_fill_dir;        // unit vector toward the fill light; casts no shadow
uniform vec3 u_fill_colour;
uniform vec3 u_sky_ambient;     // hemisphere ambient from above ...
uniform vec3 u_ground_ambient;  // ... and from below

uniform bool u_shadows;
uniform sampler2DShadow u_shadow_map;  // depth from the key light, compare mode on
uniform mat4 u_light_view_proj;        // world → key light clip space (orthographic)
uniform float u_shadow_texel;          // 1 / shadow map side
uniform float u_pcf_spread;            // distance between PCF taps, in texels
uniform float u_normal_offset;         // metres along the normal before the lookup (anti-acne)

vec3 srgb_to_linear(vec3 c) { return pow(c, vec3(2.2)); }
vec3 linear_to_srgb(vec3 c) { return pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)); }

// Fraction of the key light reaching `p` (1 lit, 0 in shadow): percentage-closer filtering over
// a 3x3 grid of bilinear depth comparisons u_pcf_spread texels apart, a penumbra about
// 2 spreads + 1 texel wide. (A 5x5 grid cost 30% more per frame on llvmpipe for little gain.)
float key_visibility(vec3 p, vec3 n) {
  if (!u_shadows) return 1.0;
  vec4 clip = u_light_view_proj * vec4(p + n * u_normal_offset, 1.0);
  vec3 uvz = clip.xyz / clip.w * 0.5 + 0.5;
  if (uvz.z >= 1.0) return 1.0;
  float lit = 0.0;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      lit += texture(u_shadow_map,
                     vec3(uvz.xy + vec2(i, j) * (u_pcf_spread * u_shadow_texel), uvz.z));
  return lit / 9.0;
}

// Diffuse light arriving at a surface with unit normal n (without the surface's colour).
vec3 diffuse_light(vec3 n, float visibility) {
  vec3 ambient = mix(u_ground_ambient, u_sky_ambient, 0.5 + 0.5 * n.y);
  return ambient + u_key_colour * max(dot(n, u_key_dir), 0.0) * visibility +
         u_fill_colour * max(dot(n, u_fill_dir), 0.0);
}
