// Ground with an anti-aliased grid: thin lines every u_params.z metres, stronger every
// u_params.w lines, and the x / z axes tinted so orientation is readable in screenshots.

in vec3 v_world_pos;
out vec4 frag_color;

float grid_line(vec2 coord) {
  // Distance to the nearest line in pixels, using screen-space derivatives for a 1 px wide line.
  vec2 d = abs(fract(coord - 0.5) - 0.5) / max(fwidth(coord), vec2(1e-6));
  return 1.0 - clamp(min(d.x, d.y), 0.0, 1.0);
}

void main() {
  vec2 xz = v_world_pos.xz;
  float minor = grid_line(xz / u_params.z);
  float major = grid_line(xz / (u_params.z * u_params.w));
  vec3 albedo = u_ground_albedo.rgb;
  albedo = mix(albedo, u_grid_color.rgb, 0.35 * minor);
  albedo = mix(albedo, u_grid_color.rgb, 0.8 * major);
  vec2 axis_d = abs(xz) / max(fwidth(xz), vec2(1e-6));
  albedo = mix(albedo, vec3(0.55, 0.12, 0.10), 1.0 - clamp(axis_d.y - 0.5, 0.0, 1.0));  // x axis
  albedo = mix(albedo, vec3(0.10, 0.18, 0.55), 1.0 - clamp(axis_d.x - 0.5, 0.0, 1.0));  // z axis
  vec3 color = shade_surface(albedo, vec3(0.0, 1.0, 0.0), v_world_pos);
  frag_color = to_display(apply_fog(color, v_world_pos));
}
