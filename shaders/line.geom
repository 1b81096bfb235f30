#version 450 core
// Expands each edge into a screen-aligned quad u_width_px wide (core profile has no wide
// lines). Depth is interpolated along the edge, so the surface still hides back edges.

layout(lines) in;
layout(triangle_strip, max_vertices = 4) out;

uniform vec2 u_viewport;   // framebuffer size in pixels
uniform float u_width_px;  // line width in framebuffer pixels

in vec3 g_colour[];
out vec3 f_colour;

void main() {
  vec4 a = gl_in[0].gl_Position;
  vec4 b = gl_in[1].gl_Position;
  if (a.w <= 0.0 || b.w <= 0.0) return;  // behind the camera: never happens for framed views
  vec2 sa = a.xy / a.w * 0.5 * u_viewport;
  vec2 sb = b.xy / b.w * 0.5 * u_viewport;
  vec2 dir = sb - sa;
  float len = length(dir);
  dir = len > 1e-6 ? dir / len : vec2(1.0, 0.0);
  // Half a width to each side, and half a width past each end so joints close.
  vec2 side = vec2(-dir.y, dir.x) * (0.5 * u_width_px);
  vec2 along = dir * (0.5 * u_width_px);
  vec2 to_ndc = 2.0 / u_viewport;
  vec2 offsets[4] = vec2[](-along - side, -along + side, along - side, along + side);
  for (int k = 0; k < 4; ++k) {
    vec4 p = k < 2 ? a : b;
    f_colour = g_colour[k < 2 ? 0 : 1];
    gl_Position = vec4(p.xy + offsets[k] * to_ndc * p.w, p.z, p.w);
    EmitVertex();
  }
  EndPrimitive();
}
