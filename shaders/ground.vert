// A large ground quad (y = 0) that follows the camera target so the grid looks infinite.

out vec3 v_world_pos;

void main() {
  // Two triangles from gl_VertexID: no vertex buffer needed.
  const vec2 kCorners[6] = vec2[6](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1),
                                   vec2(-1, 1));
  vec2 xz = u_ground_rect.xy + kCorners[gl_VertexID] * u_ground_rect.z;
  v_world_pos = vec3(xz.x, 0.0, xz.y);
  gl_Position = u_view_proj * vec4(v_world_pos, 1.0);
}
