// Instanced linear blend skinning. Every agent's palette lives in one texture buffer (4 RGBA32F
// texels per column-major mat4); the instance attributes say where this agent's palette starts and
// how far from where it was posed the agent is drawn (a held pose of the crowd's level of detail).

uniform samplerBuffer u_palette;  // texture unit 0
// A lighter mesh level is pushed out along the bind-pose normals by this much [m], so that it
// keeps the full mesh's volume (render/mesh_lod.h); 0 for the full mesh.
uniform float u_lod_inflate_m;

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_color;
layout(location = 3) in uvec4 a_joints;
layout(location = 4) in vec4 a_weights;
layout(location = 5) in vec3 i_tint;
layout(location = 6) in uint i_palette_base;
layout(location = 8) in vec3 i_offset;  // added to every palette translation [m]

out vec3 v_world_pos;
out vec3 v_normal;
out vec3 v_color;

mat4 palette_matrix(uint joint) {
  int texel = int((i_palette_base + joint) * 4u);
  return mat4(texelFetch(u_palette, texel), texelFetch(u_palette, texel + 1),
              texelFetch(u_palette, texel + 2), texelFetch(u_palette, texel + 3));
}

void main() {
  mat4 skin = a_weights.x * palette_matrix(a_joints.x) + a_weights.y * palette_matrix(a_joints.y) +
              a_weights.z * palette_matrix(a_joints.z) + a_weights.w * palette_matrix(a_joints.w);
  // The weights sum to 1, so adding the offset once equals adding it to each palette matrix.
  vec4 world = skin * vec4(a_position + a_normal * u_lod_inflate_m, 1.0);
  world.xyz += i_offset * world.w;
  v_world_pos = world.xyz;
  // Palettes are rigid (or uniformly scaled) per joint, so the blended upper 3x3 is a good enough
  // normal matrix; the fragment shader renormalises.
  v_normal = mat3(skin) * a_normal;
  v_color = a_color * i_tint;
  gl_Position = u_view_proj * world;
}
