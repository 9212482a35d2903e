// Lit surface for agents and walls.

in vec3 v_world_pos;
in vec3 v_normal;
in vec3 v_color;

out vec4 frag_color;

void main() {
  // Vertex normals are trusted over winding: generated meshes need not wind consistently.
  vec3 n = normalize(v_normal);
  vec3 color = shade_surface(v_color, n, v_world_pos);
  frag_color = to_display(apply_fog(color, v_world_pos));
}
