#pragma once
/// Writing geometry images: float EXR with every sample attribute, PNG previews.

#include <string>

#include "mcgim/geometry_image.h"

namespace mcgim {

/// Writes a float OpenEXR image of W×H pixels with channels R, G, B (position, model units),
/// N.X, N.Y, N.Z (normal), `defined` (1 or 0), `chart` and `group` (ids, −1 when undefined;
/// exact as floats up to 2^24). OpenEXR stores channels sorted by name: read them by name.
/// Row 0 of the file is the image's top (sample row H − 1). Written atomically. For a mesh so
/// far from the origin that 32-bit floats would blur it (by more than 1e-5 of its diagonal),
/// R, G, B are relative to the header attribute `isocharts:position_origin` ("x y z"); without
/// that attribute they are absolute.
/// \throw isochart::Error when the file cannot be written.
void write_exr(const GeometryImage& image, const std::string& path);

/// Writes an 8-bit RGB preview (PNG, or any format isochart::write_image writes, by extension):
/// normals mapped to colours (n + 1)/2, undefined samples black. Same row order as write_exr.
/// \throw isochart::InputError for an unknown extension, isochart::Error when writing fails.
void write_normal_preview(const GeometryImage& image, const std::string& path);

}  // namespace mcgim
