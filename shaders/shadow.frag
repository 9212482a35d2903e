in vec2 v_local;
in vec3 v_world_pos;
out vec4 frag_color;

void main() {
  float r = length(v_local);
  // Dark core under the body, smooth falloff to zero at the rim so neighbours blend seamlessly.
  float a = u_params.y * (1.0 - smoothstep(0.3, 1.0, r)) * (1.0 - fog_factor(v_world_pos));
  frag_color = vec4(0.0, 0.0, 0.0, a);
}
