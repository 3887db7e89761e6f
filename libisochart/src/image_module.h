#pragma once
// Internal: the interface between libisochart's image functions and the module that does the
// actual file I/O through OpenImageIO (libisocharts_imageio.so, loaded on first use).
//
// Why a module: OpenImageIO pulls in some 250 shared libraries (OpenCV, FFmpeg, GStreamer,
// ...) whose dynamic linking costs about 0.5 s at every start of every program that links it,
// even when no image is touched. Most runs (atlas, remesh, stats, each test process) never
// read or write an image, so only the runs that do pay that cost, once.
//
// Plain C types only, so the two sides need not agree on anything but this header.

#include <cstddef>

extern "C" {

/// Bumped whenever the struct below changes; the loader refuses a module with another.
#define ISOCHARTS_IMAGE_MODULE_ABI 3

/// Results of the module's calls. Messages are one line, without the file name.
enum IsochartsImageStatus {
  kIsochartsImageOk = 0,
  /// Reading: the file is unreadable, corrupt, too large, ...; writing: the format cannot hold
  /// the image (PNM and alpha, ICO over 256x256).
  kIsochartsImageInputError = 1,
  kIsochartsImageUnsupported = 2,  ///< no writer for the extension
  kIsochartsImageError = 3,        ///< anything else (a failed write, out of memory)
};

struct IsochartsImageModule {
  int abi;
  /// Reads the first subimage as float, alpha straight. On success `*pixels` holds
  /// width·height·channels values (row-major, top row first), to be released with
  /// free_pixels, and `names` the channel names, each followed by '\n' (truncated to
  /// names_size, always NUL-terminated), `*bits` the file's bits per channel (8, 16, or 32 for
  /// floating point). Refuses images of more than max_values values.
  int (*read)(const char* path, long long max_values, int* width, int* height, int* channels, int* bits,
              float** pixels, char* names, std::size_t names_size, char* message, std::size_t message_size);
  void (*free_pixels)(float* pixels);
  /// Writes `pixels` (width·height, `stride` floats apart, the first `channels` of each) to
  /// `path` in the format of its extension, `bits` per channel: 32 (float), 16 or 8; a format
  /// that cannot hold 16 bits gets 8 (JPEG), one that holds floats only gets floats. `alpha` is the
  /// alpha channel's index or −1. `names` ('\n'-separated, one per channel) and
  /// `attributes` (key, value, key, value, ..., NULL) may be NULL. Nothing is left at
  /// `path` when the write fails.
  int (*write)(const char* path, int width, int height, int channels, int stride, const float* pixels,
               int bits, int alpha, const char* names, const char* const* attributes, char* message,
               std::size_t message_size);
  /// 1 when there is a writer for the extension of `path` (nothing is created), else 0.
  int (*can_write)(const char* path);
};

/// The module's one exported symbol.
const IsochartsImageModule* isocharts_image_module();
typedef const IsochartsImageModule* (*IsochartsImageModuleEntry)();

}  // extern "C"
