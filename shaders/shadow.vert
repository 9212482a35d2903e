// Contact shadow: one soft disc per visible agent, lying just above the ground.


layout(location = 7) in vec4 i_ground;  // agent (x, y, z) [m], shadow radius [m]

out vec2 v_local;  // [-1, 1] across the disc
out vec3 v_world_pos;

void main() {
  const vec2 kCorners[6] = vec2[6](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1),
                                   vec2(-1, 1));
  v_local = kCorners[gl_VertexID];
  // Lifted by 1 cm so it wins the depth test against the ground without polygon offset.
  v_world_pos = vec3(i_ground.x + v_local.x * i_ground.w, 0.01,
                     i_ground.z + v_local.y * i_ground.w);
  gl_Position = u_view_proj * vec4(v_world_pos, 1.0);
}
