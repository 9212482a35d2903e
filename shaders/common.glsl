// Prepended (after the #version line) to every stage: the per-frame uniform block and the shared
// lighting, fog and gamma functions. Lighting is computed in linear RGB and converted to display
// gamma once at the end, so mesh colours and tints combine linearly and the framebuffer can stay
// plain RGBA8. The block layout must match FrameBlock in render/crowd_renderer.cc.

layout(std140) uniform Frame {
  mat4 u_view_proj;
  vec4 u_eye;            // xyz: camera position [m]
  vec4 u_sun_dir;        // xyz: unit vector toward the sun
  vec4 u_sun_color;      // rgb: linear irradiance scale
  vec4 u_sky_color;      // rgb: hemisphere ambient from above
  vec4 u_ground_color;   // rgb: hemisphere ambient from below (bounce light)
  vec4 u_fog;            // rgb: linear fog / clear colour, a: density [1/m] (0 = no fog)
  vec4 u_params;         // x: rim strength, y: shadow opacity, z: grid spacing [m], w: major every
  vec4 u_ground_albedo;  // rgb
  vec4 u_grid_color;     // rgb
  vec4 u_ground_rect;    // xy: centre (x, z) [m], z: half extent [m]
};

vec3 shade_surface(vec3 albedo, vec3 n, vec3 world_pos) {
  vec3 ambient = mix(u_ground_color.rgb, u_sky_color.rgb, 0.5 + 0.5 * n.y);
  float diffuse = max(dot(n, u_sun_dir.xyz), 0.0);
  vec3 view_dir = normalize(u_eye.xyz - world_pos);
  // A rim term separates agents from the ground and from each other in dense crowds.
  float rim = pow(1.0 - max(dot(n, view_dir), 0.0), 3.0) * u_params.x;
  return albedo * (ambient + u_sun_color.rgb * diffuse) + rim * u_sky_color.rgb;
}

float fog_factor(vec3 world_pos) { return 1.0 - exp(-u_fog.a * length(world_pos - u_eye.xyz)); }

vec3 apply_fog(vec3 color, vec3 world_pos) { return mix(color, u_fog.rgb, fog_factor(world_pos)); }

vec4 to_display(vec3 linear_rgb) { return vec4(pow(max(linear_rgb, 0.0), vec3(1.0 / 2.2)), 1.0); }
