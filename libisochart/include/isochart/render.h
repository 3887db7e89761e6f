#pragma once
/// A headless software rasterizer for previews and figures: shaded, chart-coloured or
/// textured views of a mesh, and the texture-space layout of an atlas (as in the Iso-charts
/// paper's figures). Deterministic: the same input gives the same pixels on any thread count.

#include <vector>

#include "isochart/image.h"
#include "isochart/mesh.h"

namespace isochart {

/// What colours a surface before lighting.
enum class ColorMode {
  Shaded,    ///< uniform light grey
  Charts,    ///< one colour per chart (RenderOptions::face_charts, else Mesh::face_groups,
             ///< else the mesh's UV charts), adjacent charts in different colours
  Textured,  ///< RenderOptions::texture looked up bilinearly through the per-corner UVs
};

struct RenderOptions {
  int width = 800;   ///< output width in pixels, all views together
  int height = 800;  ///< output height in pixels
  /// Number of views (1–8), side by side in equal columns, in this order: front (camera on
  /// +z), right (+x), back, left, top, bottom, front-right, back-left. The four side views
  /// look 15° down; every view is fitted to the model's projected extent.
  int views = 1;
  ColorMode color = ColorMode::Shaded;
  const Image* texture = nullptr;  ///< the texture for ColorMode::Textured (not owned)
  /// How the texture is read along an axis that some texture coordinate leaves [0, 1] along
  /// (the material's sampler); along the others it is clamped, so an atlas does not bleed
  /// across the texture's borders.
  TextureWrap texture_wrap;
  /// A model of several materials (ColorMode::Textured): face f reads
  /// materials[face_material[f]] instead of `texture`, each material with its own wrap (clamped
  /// along an axis its faces' coordinates stay within [0, 1] along, as `texture`); a material
  /// without a texture shows its colour.
  struct Material {
    const Image* texture = nullptr;  ///< not owned; null: `colour`
    TextureWrap wrap;
    Vec3d colour{1, 1, 1};
  };
  std::vector<Material> materials;
  std::vector<int> face_material;  ///< #F indices into `materials`, with `materials`
  /// Per-face chart ids (#F, ≥ 0) for ColorMode::Charts; overrides face_groups and UVs.
  std::vector<int> face_charts;
  bool wireframe = false;    ///< overlay the triangle edges (1 px dark lines)
  bool perspective = true;   ///< perspective (30° field of view) or orthographic
  bool transparent = false;  ///< RGBA with a transparent background instead of RGB on white
  int supersample = 2;       ///< samples per pixel along each axis, 1–4 (anti-aliasing)
  Vec3d up{0, 1, 0};         ///< the model's up direction; views turn around it
};

/// Renders `mesh` into an RGB image (RGBA when `transparent`) of width × height pixels:
/// z-buffered triangles, Lambert shading from a key and a fill light plus ambient and a
/// little specular, smooth normals except across creases sharper than 60°, back faces lit
/// like front faces but darker. Textured mode uses perspective-correct UV interpolation.
/// Textures are looked up with clamping when every UV lies in [0, 1] (an atlas), repeating
/// otherwise.
/// \throw InputError for invalid options (views, supersample, or a size beyond 16384 per side
///        or 2^25 samples = width × height × supersample²), an empty mesh, indices out of
///        range, or a colour mode the mesh cannot provide (no charts, no UVs, no texture), or
///        materials with face_material of the wrong size or out of range.
Image render_mesh(const Mesh& mesh, const RenderOptions& options = {});

/// Draws the atlas in texture space into an RGB image of width × height pixels on white:
/// each UV chart filled in its colour, triangle edges thin and slightly darker, chart
/// boundaries dark. The [0, 1]² texture square is shown (framed in grey) when every UV lies
/// inside it; otherwise the UV bounding box fills the image. Aspect ratio is preserved, with
/// a unit of u `texture_aspect` (the texture's width / height) times as long as one of v, so
/// the layout of a 1024×256 atlas is drawn as the texture looks.
/// Rendered with kUvLayoutSupersample² samples a pixel, so width × height is limited to 2^23 pixels.
/// \throw InputError if the mesh has no UVs or the size or aspect is invalid.
constexpr int kUvLayoutSupersample = 2;
Image render_uv_layout(const Mesh& mesh_with_uvs, int width, int height, double texture_aspect = 1.0);

/// Colours (RGB in [0, 1]) for charts: `face_chart` gives a chart id per face (ids in
/// [0, num_charts)); charts sharing a mesh edge get different colours from a palette of
/// light, distinct hues. Deterministic.
std::vector<Vec3d> chart_colors(const Mesh& mesh, const std::vector<int>& face_chart, int num_charts);

}  // namespace isochart
