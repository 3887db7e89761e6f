#pragma once
/// Float images and their file I/O through OpenImageIO (PNG, JPG, EXR, TIFF, ... by extension).
/// The I/O runs in a module, libisocharts_imageio.so, loaded on the first read or write (see
/// src/image_module.h for why): the file $ISOCHARTS_IMAGE_MODULE names when it is set, otherwise
/// the one next to the running program, then the one where the build put it.

#include <string>
#include <utility>
#include <vector>

namespace isochart {

/// A float image, `height` rows of `width` pixels of `channels` values, row-major, top row
/// first: the value of channel c at column x, row y is pixels[(y * width + x) * channels + c].
/// Colours are in [0, 1] (8-bit files are scaled on read and clamped on write); float formats
/// (EXR) hold any value. Alpha, when present (2 or 4 channels, last), is straight (colours not
/// premultiplied). A texture coordinate (u, v) = (0, 0) is the bottom-left corner.
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> pixels;  ///< width × height × channels values
  /// Optional channel names (as stored in the file; EXR keeps them sorted). Written when there
  /// is one per channel, and then no channel is taken for alpha unless it is named "A".
  std::vector<std::string> channel_names;
  /// Bits per channel of the file it was read from (8, 16, or 32 for floating point); write_image
  /// writes 16-bit PNG, TIFF and PNM files when this is 16 or more, 8-bit ones otherwise.
  int bits = 8;
  /// Optional string metadata written with the image (key, value), e.g. {"compression", "zip"}.
  std::vector<std::pair<std::string, std::string>> attributes;

  Image() = default;
  /// An image filled with `value` in every channel.
  Image(int width_, int height_, int channels_, float value = 0.0f)
      : width(width_),
        height(height_),
        channels(channels_),
        pixels(static_cast<std::size_t>(width_) * height_ * channels_, value) {}

  bool empty() const { return pixels.empty(); }
  /// The alpha channel, or -1: the one named "A" when every channel is named, else the last of
  /// grey+alpha or RGBA.
  int alpha_channel() const {
    if (static_cast<int>(channel_names.size()) == channels) {
      for (int c = 0; c < channels; ++c)
        if (channel_names[c] == "A") return c;
      return -1;
    }
    return channels == 2 || channels == 4 ? channels - 1 : -1;
  }
  float& at(int x, int y, int c) { return pixels[(static_cast<std::size_t>(y) * width + x) * channels + c]; }
  float at(int x, int y, int c) const {
    return pixels[(static_cast<std::size_t>(y) * width + x) * channels + c];
  }
};

/// How texture lookups treat coordinates outside [0, 1]: the border texel, the texture again,
/// or the texture mirrored every other time (glTF's CLAMP_TO_EDGE, REPEAT, MIRRORED_REPEAT).
enum class Wrap { Clamp, Repeat, Mirror };

/// How a material reads its texture outside [0, 1] along u and along v (glTF sampler
/// wrapS / wrapT; OBJ `-clamp on` clamps both). Both formats repeat unless told otherwise.
struct TextureWrap {
  Wrap u = Wrap::Repeat;
  Wrap v = Wrap::Repeat;
};

/// Bilinear lookup at texture coordinate (u, v) (v = 0 is the bottom row, texel centres at
/// half-integers), wrapped along u by `wrap_u` and along v by `wrap_v`. Writes
/// `image.channels` values to `out`.
void sample_bilinear(const Image& image, double u, double v, float* out, Wrap wrap_u, Wrap wrap_v);
inline void sample_bilinear(const Image& image, double u, double v, float* out, Wrap wrap = Wrap::Clamp) {
  sample_bilinear(image, u, v, out, wrap, wrap);
}

/// Gives every texel not `filled` (one flag per texel, updated) the values of the nearest
/// filled texel (4-neighbour steps, first reached wins in a fixed order), but for channel
/// `keep` (e.g. an alpha that stays 0), so that texels outside a texture's charts do not
/// bleed other colours into filtered lookups and mipmaps. Nothing changes when none is filled.
void fill_from_nearest(Image& image, std::vector<char>& filled, int keep = -1);

/// `image` resized to `width`×`height` by area averaging (each new texel the mean of the old
/// texels it covers, in proportion): a box-filtered reduction, for shrinking without aliasing.
Image resize_area(const Image& image, int width, int height);

/// Reads the first subimage of an image file; 8-bit and 16-bit data are scaled to [0, 1].
/// Fills `channel_names`.
/// \throw InputError(path, ...) when the file is missing, unreadable, corrupt or in a format
///        OpenImageIO does not know; Error when the image I/O module cannot be loaded.
Image read_image(const std::string& path);

/// Writes `image` to `path` in the format given by the extension: float for .exr/.hdr/.pfm,
/// 16-bit PNG/TIFF/PNM for an image of 16 or more `bits`, 8-bit otherwise (values clamped to
/// [0, 1]; JPEG drops an alpha channel). The image is
/// written to a temporary file in the same directory (same extension) and renamed over
/// `path` only when complete, so `path` never holds a partial image.
/// \throw InputError(path, ...) for an unknown extension or a missing directory,
///        Error when writing fails (the temporary file is removed).
void write_image(const std::string& path, const Image& image);

/// What write_image would refuse for its path before writing anything: no extension, or no
/// writer for it. Commands check their image outputs with it before any work.
/// \throw InputError(path, ...) naming the problem.
void check_image_output(const std::string& path);

}  // namespace isochart
