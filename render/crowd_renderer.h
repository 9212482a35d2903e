#pragma once
// Draws a crowd of skinned agents with instanced GPU skinning, plus the scene around them: a ground
// grid, walls, contact shadows and batched debug lines.
//
// Per frame:  upload_palettes(all agents' palettes)  ->  add_line(...)*  ->  draw(camera, agents)
// - All palettes go to the GPU in one upload into a texture buffer (4 RGBA32F texels per mat4).
// - Agents outside the view frustum are culled on the CPU; each survivor gets a level of detail of
//   its mesh from its size on screen (render/mesh_lod.h); they are grouped by mesh and level in a
//   preallocated instance array and each (mesh, level) is drawn with ONE glDrawElementsInstanced.
// - Buffers grow geometrically when a frame needs more; in a steady state nothing is allocated.
// Needs a current OpenGL 3.3 core context (GlContext) for every call, including destruction.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "animation/mesh.h"
#include "common/status.h"
#include "render/camera.h"
#include "render/gl_api.h"
#include "render/mesh_lod.h"
#include "render/shader_program.h"

namespace gk {

// One agent to draw this frame, skinned with palette block `palette` of upload_palettes(): the
// palettes may stay in whatever order their producer keeps them (a mediator's slots), no copy.
struct AgentDraw {
  glm::vec3 position{0.0f};  // ground point under the agent [m]: culling sphere and contact shadow
  glm::vec3 tint{1.0f};      // linear RGB multiplier of the mesh colours (per-agent variation)
  int mesh = 0;              // id returned by add_mesh
  // Palette block of this agent [Limit: < blocks uploaded]; negative (the default): block i for
  // agent i of draw(), for palettes uploaded in draw order.
  int palette = -1;
  // Added to the translation of every matrix of its palette block [m]: a pose made at one place
  // drawn at another (a crowd's level of detail holds far agents' poses and moves them with their
  // roots this way, one vector per agent instead of a rewrite of its palette).
  glm::vec3 offset{0.0f};
};

// An upright box standing on or above the ground (exhibits, props): lit like the walls.
struct PropBox {
  glm::vec3 center{0.0f};       // [m]
  glm::vec3 half_size{0.5f};    // [m] along its local x (width), y (up), z (depth) [Limit: > 0]
  float yaw_rad = 0.0f;         // heading of its local +z about +y (+z -> (sin, 0, cos))
  glm::vec3 color{1.0f};        // linear RGB
};

// Look of the scene; colours are linear RGB unless noted. Safe to change between frames.
struct RenderSettings {
  glm::vec3 sun_direction{0.45f, 0.8f, 0.4f};  // toward the sun (normalised on use)
  glm::vec3 sun_color{1.25f, 1.18f, 1.05f};
  glm::vec3 sky_color{0.30f, 0.36f, 0.46f};
  glm::vec3 ground_bounce_color{0.16f, 0.14f, 0.12f};
  glm::vec3 fog_color{0.55f, 0.62f, 0.72f};  // also the background
  float fog_density_per_m = 0.006f;          // [1/m] [Limit: >= 0]
  float rim_strength = 0.25f;                // [0, 1]
  glm::vec3 ground_albedo{0.36f, 0.36f, 0.34f};
  glm::vec3 grid_color{0.12f, 0.12f, 0.12f};
  float grid_spacing_m = 1.0f;          // [m] [Limit: > 0]
  float grid_major_every = 5.0f;        // every n-th grid line is drawn stronger
  float ground_half_extent_m = 250.0f;  // the ground quad follows the camera target
  float shadow_opacity = 0.6f;          // peak darkness of a contact shadow [0, 1]
  float shadow_radius_scale = 1.0f;     // times the mesh's horizontal radius
  float wall_height_m = 1.0f;           // [m] [Limit: > 0]
  float wall_thickness_m = 0.15f;       // [m] [Limit: > 0]
  glm::vec3 wall_color{0.55f, 0.50f, 0.45f};
  bool draw_ground = true;
  bool draw_shadows = true;
  bool draw_walls = true;
  bool draw_lines = true;
  bool lines_on_top = false;    // true: debug lines ignore depth (overlays stay readable)
  bool cull_agents = true;      // frustum culling (off only to measure its effect)
  bool cull_back_faces = true;  // agents only; add_mesh makes the winding follow the normals
  // Lighter meshes for agents small on screen (off: every agent with its full mesh).
  bool mesh_lod = true;
  MeshLodSelection mesh_lod_selection;  // when a lighter level is good enough (mesh_lod.h)
};

// Counters of the last draw() (and of add_line since then).
struct RenderStats {
  int draw_calls = 0;          // every glDraw* issued by draw()
  int skinned_draw_calls = 0;  // instanced agent draws: one per mesh that has visible agents
  int agents_submitted = 0;
  int agents_visible = 0;
  int agents_culled = 0;
  int lines_drawn = 0;
  int lines_dropped = 0;        // add_line calls beyond max_debug_lines, since the last draw
  int triangles_drawn = 0;      // debug triangles (add_triangle)
  int triangles_dropped = 0;    // add_triangle calls beyond max_debug_triangles
  int64_t agent_triangles = 0;  // skinned triangles drawn: instances times their level's triangles
  std::array<int, kMaxMeshLods> agents_per_lod{};  // visible agents drawn with each mesh level
};

struct RendererConfig {
  int initial_agent_capacity = 1024;  // instances before the first growth
  int initial_joints_per_agent = 64;  // palette capacity = agents * joints before growth
  int max_debug_lines = 1 << 16;      // fixed; further add_line calls are dropped and counted
  int max_debug_triangles = 1 << 14;  // fixed; likewise for add_triangle
};

class CrowdRenderer {
 public:
  CrowdRenderer();
  ~CrowdRenderer();
  CrowdRenderer(const CrowdRenderer&) = delete;
  CrowdRenderer& operator=(const CrowdRenderer&) = delete;

  // Builds the shaders and buffers. Errors carry the shader file and the driver log.
  Status init(const RendererConfig& config = {});

  // Uploads a bind-pose mesh; returns its id (0, 1, ...). Validates sizes, indices and joints.
  // Triangles are re-wound to face where their vertex normals point (front = counter-clockwise),
  // which lets the renderer cull back faces even when a generator winds some triangles clockwise.
  // It also builds the mesh's chain of lighter levels (build_mesh_lods with `lod_options`).
  Result<int> add_mesh(const SkinnedMesh& mesh, const MeshLodOptions& lod_options = {});
  int num_meshes() const { return static_cast<int>(meshes_.size()); }
  // Levels of detail of a mesh (1 = the full mesh only), and each level's triangles and
  // bind-pose error [m]. `mesh` and `level` must be in range.
  int num_mesh_lods(int mesh) const { return meshes_[mesh].num_lods; }
  int mesh_lod_triangles(int mesh, int level) const { return meshes_[mesh].lod_count[level] / 3; }
  float mesh_lod_error_m(int mesh, int level) const { return meshes_[mesh].lod_error_m[level]; }

  // All agents' skinning palettes, block after block, joints_per_agent matrices each (world-space
  // palettes: model[j] * inverse_bind[j] with the agent's placement in model); AgentDraw::palette
  // picks an agent's block. One GPU upload.
  Status upload_palettes(std::span<const glm::mat4> palettes, int joints_per_agent);

  // Walls as 2D segments on the ground, (x0, z0, x1, z1) [m] each, drawn as low boxes with the
  // wall_* settings current at this call. Static: call when the scenario changes, not per frame.
  Status set_walls(std::span<const glm::vec4> segments);
  // Static boxes (exhibits and other props); replaces the previous set. Static like the walls.
  Status set_props(std::span<const PropBox> boxes);

  // Debug line in world space with a display (sRGB) colour; batched and drawn by the next draw()
  // in one call, then cleared.
  void add_line(const glm::vec3& a, const glm::vec3& b, const glm::vec3& color);
  // Translucent debug triangle (display colour, alpha in w; both sides), batched like the lines
  // and drawn just before them (fans, wedges). Beyond max_debug_triangles they are dropped.
  void add_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c,
                    const glm::vec4& color);

  // Clears and renders the frame into the bound framebuffer (viewport_px = its size).
  Status draw(const OrbitCamera& camera, glm::ivec2 viewport_px, std::span<const AgentDraw> agents);
  // Same, into the rectangle at origin_px (GL convention: from the bottom-left corner) of size
  // viewport_px; only that rectangle is cleared, so two calls make a split screen.
  Status draw_region(const OrbitCamera& camera, glm::ivec2 origin_px, glm::ivec2 viewport_px,
                     std::span<const AgentDraw> agents);

  RenderSettings& settings() { return settings_; }
  const RenderSettings& settings() const { return settings_; }
  const RenderStats& stats() const { return stats_; }

 private:
  struct MeshGpu {
    GLuint vao = 0, vertex_buffer = 0, index_buffer = 0;
    // Levels of detail: level l is lod_count indices from index lod_first of the one index
    // buffer, over level l's copy of the vertices in the one vertex buffer (its own normals).
    int num_lods = 1;
    std::array<GLsizei, kMaxMeshLods> lod_first{}, lod_count{};
    std::array<float, kMaxMeshLods> lod_error_m{};
    std::array<float, kMaxMeshLods> lod_inflate_m{};  // MeshLodLevel::inflate_m
    int num_joints = 0;
    float center_height_m = 0.0f;  // bounding sphere centre above the agent's ground point
    float radius_m = 0.0f;         // bounding sphere radius, with margin for animation
    float shadow_radius_m = 0.0f;
    // True when the normals decide the winding of (nearly) every triangle, so back faces can be
    // culled: on llvmpipe that removes ~40% of the raster work of a big crowd.
    bool cull_back_faces = false;
  };
  struct GpuInstance {  // matches the instance attributes of skinned.vert / shadow.vert
    glm::vec3 tint;
    uint32_t palette_base;  // first matrix of this agent in the palette buffer
    glm::vec4 ground;       // xyz: ground point [m], w: shadow radius [m]
    glm::vec4 offset;       // xyz: AgentDraw::offset [m], w: unused
  };
  struct LineVertex {  // matches lines.vert; lines have alpha 1
    glm::vec3 position;
    glm::vec4 color;
  };

  int cull_and_group(const OrbitCamera& camera, glm::ivec2 viewport_px,
                     std::span<const AgentDraw> agents);
  void upload_frame_block(const OrbitCamera& camera, glm::ivec2 viewport_px);
  void draw_ground();
  void draw_walls();
  void draw_triangles();
  void draw_agents();
  void draw_shadows(int num_visible);
  void draw_lines();
  void release();

  bool initialized_ = false;
  RendererConfig config_;
  RenderSettings settings_;
  RenderStats stats_;
  ShaderProgram skinned_program_, static_program_, ground_program_, shadow_program_, lines_program_;
  GLint lod_inflate_uniform_ = -1;  // u_lod_inflate_m of skinned.vert
  GLuint frame_ubo_ = 0;
  GLuint palette_buffer_ = 0, palette_texture_ = 0;
  int64_t palette_capacity_matrices_ = 0;
  int num_palette_agents_ = 0;
  int joints_per_agent_ = 0;
  GLint max_texture_buffer_texels_ = 0;
  GLuint instance_buffer_ = 0;
  int instance_capacity_ = 0;
  GLuint empty_vao_ = 0;  // the ground needs a bound VAO but no attributes
  GLuint shadow_vao_ = 0;
  GLuint wall_vao_ = 0, wall_buffer_ = 0;
  GLsizei num_wall_vertices_ = 0;
  GLuint prop_vao_ = 0, prop_buffer_ = 0;
  GLsizei num_prop_vertices_ = 0;
  GLuint line_vao_ = 0, line_buffer_ = 0;
  GLuint triangle_vao_ = 0, triangle_buffer_ = 0;
  std::vector<MeshGpu> meshes_;
  // Per-frame scratch, grown only when a frame brings more agents or lines than ever before.
  std::vector<GpuInstance> instances_;
  std::vector<int> visible_;          // agent indices that survived culling
  std::vector<uint8_t> visible_lod_;  // and the mesh level each is drawn with
  // First instance in instances_ and number of visible instances of each (mesh, level), at
  // mesh * kMaxMeshLods + level.
  std::vector<int> bucket_first_;
  std::vector<int> bucket_count_;
  // The level each palette block was drawn with last (kNoLod: none yet), for the hysteresis:
  // a block is one agent for as long as it lives (a mediator slot). Grown with the palettes.
  static constexpr uint8_t kNoLod = 0xff;
  std::vector<uint8_t> lod_of_block_;
  std::vector<LineVertex> lines_;      // reserved to 2 * max_debug_lines at init
  std::vector<LineVertex> triangles_;  // reserved to 3 * max_debug_triangles at init
  int dropped_lines_ = 0;
  int dropped_triangles_ = 0;
};

}  // namespace gk
