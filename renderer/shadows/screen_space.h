#pragma once
// The screen-space shadow techniques (EDTSM, EDTSSM, erosion) share one frame shape:
//   gbuffer   (raster) the scene with the input hard shadows; writes world position, the eye
//             depth signed by the input test and shadow-map coordinates per pixel (the camera
//             depth is shared)
//   post passes (compute) that read the G-buffer and the shadow map and produce, per pixel, the
//             visibility (EDTSM, EDTSSM) or the eroded penumbra width (erosion)
//   shading   (raster, depth test LEQUAL against the G-buffer's depth) lights the scene with it.
// This class owns the G-buffer and the post passes' images and programs; each technique's post
// passes live in its own file (techniques/edtsm.cpp, edtssm.cpp, erosion.cpp: TechniqueEntry::post)
// and are built from the pieces below. Choices not fixed by the papers: docs/alternatives.md.
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <penumbra/gl/objects.h>
#include <penumbra/gl/shader_library.h>
#include <penumbra/gl/timer.h>
#include <penumbra/shadows/edt.h>
#include <penumbra/shadows/scoped_pass.h>
#include <penumbra/shadows/settings.h>

namespace penumbra::shadows {

// The camera's metric as the post passes need it.
struct ScreenView {
  bool perspective = true;
  // Pixels per world unit: perspective z_screen * height_px (divided by the eye depth in the
  // shaders, z_screen = 1 / (2 tan(fov_y / 2))); orthographic height_px / view height.
  float px_scale = 1;
};

struct PostPassContext {
  ScreenView view;
  // Sets the light-frame and shadow-map uniforms (common.glsl, shadow_pcss.glsl) on a program.
  std::function<void(const gl::Program&)> set_technique_uniforms;
  PassReport report;  // the frame's timer, work counter and pass list (scoped_pass.h)
};

class ScreenSpace {
 public:
  explicit ScreenSpace(const gl::ShaderLibrary& shaders);
  ~ScreenSpace();

  // (Re)allocates the G-buffer at the size of `camera_depth`, whose framebuffer shares it.
  void resize(const gl::Texture& camera_depth);
  // Colour attachments 0: world position and eye depth signed by the input shadow test (+ lit,
  // - shadowed, 0 nothing drawn), 1: shadow-map coordinates.
  const gl::Framebuffer& gbuffer_framebuffer() const { return gbuffer_fbo_; }

  // --- building blocks for the technique files ---
  int width() const { return width_; }
  int height() const { return height_; }
  // A compute program from `file` with `defines`, compiled on first use.
  const gl::Program& program(const std::string& file, const std::vector<gl::ShaderDefine>& defines = {});
  // Binds the G-buffer to units 4-6 and sets the view uniforms of screen_space.glsl.
  void bind_gbuffer(const gl::Program& p, const ScreenView& view, float depth_threshold) const;
  // Silhouette sites of the input shadows into sites() (R8UI) and, with a blocker search, the
  // penumbra width at each site into site_width() (world units).
  struct SiteSearch {
    bool laplacian = false;      // 4-neighbour cross instead of the 3x3 window
    bool blocker_search = false;
    int blocker_taps = 25;
    float search_scale = 1;
  };
  void detect_sites(const SiteSearch& search, float depth_threshold, const PostPassContext& ctx);
  Edt& edt() { return edt_; }
  // The exact EDT of the sites, then edt_penumbra.comp into scratch(0) (EDTSM, EDTSSM; each reported
  // as its own pass): `propagated_width` reads site_width() (EDTSSM's w_p), `set_uniforms` sets the
  // technique's own uniforms (u_penumbra_ws, u_beta).
  const gl::Texture& edt_penumbra(bool propagated_width, bool edge_between_pixels, float depth_threshold,
                                  const std::function<void(const gl::Program&)>& set_uniforms, const PostPassContext& ctx);
  // Edge-aware separable mean filter of `source` (RG32F: value, the G-buffer's signed depth) into
  // the returned image (the same layout).
  const gl::Texture& mean_filter(const gl::Texture& source, float filter_ws, int max_width_px, float depth_threshold,
                                 const PostPassContext& ctx);

  const gl::Texture& sites() const { return sites_; }
  const gl::Texture& site_width() const { return site_width_; }
  // Two RG32F images for intermediate results (value, signed depth).
  gl::Texture& scratch(int i) { return scratch_[i]; }
  // RG32F with a full mip chain at the image size (erosion's min-max mip-map), made on first use.
  gl::Texture& edges_mip();
  // The last frame's G-buffer position (RGBA32F; the sign of w is the input visibility).
  const gl::Texture& gbuffer_position() const { return position_; }

 private:
  const gl::ShaderLibrary& shaders_;
  std::map<std::string, gl::Program> programs_;
  gl::Sampler nearest_;
  Edt edt_;
  int width_ = 0, height_ = 0;
  GLuint depth_id_ = 0;
  gl::Texture position_, light_;
  gl::Framebuffer gbuffer_fbo_;
  gl::Texture sites_, site_width_;
  gl::Texture scratch_[2];
  gl::Texture filtered_;
  gl::Texture edges_;
};

}  // namespace penumbra::shadows
