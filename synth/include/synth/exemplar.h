#pragma once
/// Exemplar textures for surface synthesis: reading and checking them, resampling them to the
/// texel size of each MCGIM level (the exemplar's Gaussian pyramid, Wei–Levoy 2001 §3), and the
/// project's own procedural exemplars.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "isochart/image.h"

namespace synth {

/// Reads an exemplar through OpenImageIO (PNG, JPG, EXR, ...) and returns it as 3-channel RGB
/// in [0, 1]: greyscale is replicated, an alpha channel must be opaque (every value ≥ 0.999)
/// and is dropped; EXR values are clamped to [0, 1], and `clipped` (when given) receives how
/// many colour values were, so that callers can say so.
/// \throw isochart::InputError(path, ...) for a missing or unreadable file, an image smaller
///        than 4×4, transparency, or a channel count other than 1–4 without R, G, B named.
isochart::Image load_exemplar(const std::string& path, long long* clipped = nullptr);

/// Checks an in-memory exemplar the same way and converts it to RGB.
/// \throw isochart::InputError(name, ...) as load_exemplar.
isochart::Image to_rgb_exemplar(const isochart::Image& image, const std::string& name,
                                long long* clipped = nullptr);

/// The exemplar resampled so that one of its pixels covers `factor` pixels of the original
/// (factor > 1 shrinks with a Gaussian pre-filter of σ = 0.5·factor pixels, factor ≤ 1
/// magnifies bilinearly). The result is at least 4×4; `actual_factor` gives the original
/// pixels per result pixel that its integer size implies (width-wise).
struct ExemplarLevel {
  isochart::Image image;      ///< RGB
  double actual_factor = 1;   ///< original exemplar pixels per pixel of `image`
};
ExemplarLevel resample_exemplar(const isochart::Image& rgb, double factor);

/// Builds one ExemplarLevel per factor (MCGIM levels finest first: increasing factors).
std::vector<ExemplarLevel> exemplar_pyramid(const isochart::Image& rgb,
                                            const std::vector<double>& factors);

/// Correlation length of an exemplar (original pixels): along x, y and both diagonals, the
/// first lag at which the normalized autocorrelation of the colours (mean removed, channels
/// summed) falls to `threshold` or below; the longest of the four. Lags stop at half the
/// exemplar's smaller side (that value is returned when the correlation never falls). It
/// measures how far the exemplar's structure reaches: a few pixels for cells or gravel, the
/// whole row for the bricks photograph (mortar lines run across the image). Large exemplars
/// are sampled on a regular sub-grid of at most about 256² pixels per lag.
double correlation_length(const isochart::Image& rgb, double threshold = 0.1);
/// The four lengths correlation_length takes the longest of: along x, y, the diagonal (+x +y)
/// and the anti-diagonal (+x −y), in original pixels.
std::array<double, 4> correlation_lengths(const isochart::Image& rgb, double threshold = 0.1);

/// Smoothness of an exemplar at `lag` pixels (rounded, at least 1): the smaller of its
/// normalized colour autocorrelations at that lag along x and along y (1 for a constant
/// image). Near 1 when the exemplar varies little from one pixel to the next at that scale
/// (the cells exemplar: 0.92 at one pixel); low when thin lines, edges or grain carry much of
/// its variance (bricks, gravel, wicker photographs: 0.53–0.68), detail a coarser pyramid
/// level blurs away.
double exemplar_smoothness(const isochart::Image& rgb, double lag = 1);

/// Names of the procedural exemplars: "bricks", "cells", "weave", "noise".
std::vector<std::string> exemplar_names();

/// A procedural exemplar, `size`×`size` RGB, depending only on name, size and seed. All are
/// tileable (periodic over the image).
/// \throw isochart::InputError("builtin:NAME", ...) for an unknown name or size < 8.
isochart::Image make_exemplar(const std::string& name, int size = 128, std::uint64_t seed = 1);

/// "builtin:NAME" → make_exemplar(NAME), anything else → load_exemplar(path, clipped).
isochart::Image exemplar_from(const std::string& spec, long long* clipped = nullptr);

}  // namespace synth
