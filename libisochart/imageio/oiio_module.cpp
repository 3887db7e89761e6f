// The image I/O module (libisocharts_imageio.so): image files through OpenImageIO, behind the
// plain-C interface of image_module.h. libisochart loads it on the first image read or write.
//
// OIIO keeps per-thread and global error strings; every failure path reads them (which also
// clears them, so OIIO does not complain at exit).

#include <fcntl.h>
#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cerrno>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "../src/image_module.h"

namespace {

// One line from OIIO's error text: the first non-empty line.
std::string one_line(std::string message) {
  const auto start = message.find_first_not_of(" \t\r\n");
  if (start == std::string::npos) return {};
  message = message.substr(start);
  const auto end = message.find_first_of("\r\n");
  if (end != std::string::npos) message.resize(end);
  return message;
}

std::string with_detail(const std::string& message, const std::string& detail) {
  const std::string d = one_line(detail);
  return d.empty() ? message : message + " (" + d + ")";
}

int report(int status, const std::string& text, char* message, std::size_t size) {
  if (message && size > 0) {
    std::strncpy(message, text.c_str(), size - 1);
    message[size - 1] = '\0';
  }
  return status;
}

// PNG files end with the IEND chunk, JPEG files with the EOI marker. A file cut short (a full
// disk while writing, a partial download) lacks them; checking first keeps libpng from printing
// its own complaint on stderr before ours. Some writers append bytes after the marker (JPEG
// padding, PNG trailers), so it is looked for in the last 64 KiB rather than at the very end.
// 1 complete, 0 cut short, -1 another format.
// The end marker of `path`'s format: told by its first bytes for a file to read (a PNG named
// .jpg is still a PNG), by the extension for one about to be written. Empty: none checked.
std::string end_marker(const char* path, bool by_content) {
  const std::string png("IEND\xAE\x42\x60\x82", 8), jpeg("\xFF\xD9", 2);
  if (!by_content) {
    const char* dot = std::strrchr(path, '.');
    if (!dot) return {};
    std::string ext(dot + 1);
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext == "png" ? png : ext == "jpg" || ext == "jpeg" ? jpeg : std::string();
  }
  std::FILE* f = std::fopen(path, "rb");
  if (!f) return {};
  unsigned char head[8] = {0};
  const std::size_t got = std::fread(head, 1, sizeof head, f);
  std::fclose(f);
  if (got == 8 && std::memcmp(head, "\x89PNG\r\n\x1a\n", 8) == 0) return png;
  if (got >= 3 && head[0] == 0xFF && head[1] == 0xD8 && head[2] == 0xFF) return jpeg;
  return {};
}

int trailer_complete(const char* path, bool by_content) {
  const std::string marker = end_marker(path, by_content);
  if (marker.empty()) return -1;
  std::FILE* f = std::fopen(path, "rb");
  if (!f) return 0;
  std::string tail;
  if (std::fseek(f, 0, SEEK_END) == 0) {
    const long size = std::ftell(f);
    const long window = std::min<long>(size, 65536);
    if (size >= 0 && std::fseek(f, size - window, SEEK_SET) == 0) {
      tail.resize(static_cast<std::size_t>(window));
      tail.resize(std::fread(&tail[0], 1, tail.size(), f));
    }
  }
  std::fclose(f);
  return tail.find(marker) != std::string::npos ? 1 : 0;
}

int read_file(const char* path, long long max_values, int* width, int* height, int* channels, int* bits,
              float** pixels, char* names, std::size_t names_size, char* message, std::size_t message_size) {
  *pixels = nullptr;
  {
    std::FILE* f = std::fopen(path, "rb");
    const bool empty = f && std::fgetc(f) == EOF;
    if (f) std::fclose(f);
    if (empty) return report(kIsochartsImageInputError, "cannot read image: the file is empty", message, message_size);
  }
  if (trailer_complete(path, true) == 0)
    return report(kIsochartsImageInputError, "cannot read image: the file is cut short (no end marker)", message,
                  message_size);
  // Keep alpha as stored (straight): OIIO would otherwise premultiply PNG colours by alpha.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in)
    return report(kIsochartsImageInputError,
                  with_detail("cannot read image: unknown format or unreadable file", OIIO::geterror()),
                  message, message_size);
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) {
    in->geterror();
    return report(kIsochartsImageInputError,
                  "image has no pixels (" + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                      ", " + std::to_string(spec.nchannels) + " channels)",
                  message, message_size);
  }
  if (spec.depth > 1)
    return report(kIsochartsImageInputError, "volume images are not supported", message, message_size);
  const long long values = static_cast<long long>(spec.width) * spec.height * spec.nchannels;
  // Counted as four channels whatever the file holds: a grey image is expanded to RGB(A)
  // floats after reading (a 30000² grey PNG of 875 KB took 7 GB).
  const long long area = static_cast<long long>(spec.width) * spec.height;
  if (area * std::max(spec.nchannels, 4) > max_values)
    return report(kIsochartsImageInputError,
                  "image too large (" + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                      " pixels; at most " + std::to_string(max_values / 4) + " pixels, e.g. " +
                      std::to_string(static_cast<long long>(std::sqrt(static_cast<double>(max_values / 4)))) + "²)",
                  message, message_size);
  auto* data = static_cast<float*>(std::malloc(static_cast<std::size_t>(values) * sizeof(float)));
  if (!data) return report(kIsochartsImageError, "out of memory reading the image", message, message_size);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, data)) {
    const std::string detail = in->geterror();
    OIIO::geterror();
    std::free(data);
    return report(kIsochartsImageInputError,
                  with_detail("cannot read image: corrupt or truncated file", detail), message, message_size);
  }
  in->close();
  // Some readers leave warnings behind even on success; drop them.
  in->geterror();
  // A NaN or infinite texel (float EXR) would poison every filter and average it meets; it was
  // once replaced by 0 without a word.
  for (long long i = 0; i < values; ++i)
    if (!std::isfinite(data[i])) {
      long long bad = 0;
      for (long long j = i; j < values; ++j) bad += std::isfinite(data[j]) ? 0 : 1;
      const long long texel = i / spec.nchannels;
      const int c = static_cast<int>(i % spec.nchannels);
      const std::string channel = c < static_cast<int>(spec.channelnames.size()) && !spec.channelnames[c].empty()
                                      ? spec.channelnames[c]
                                      : "channel " + std::to_string(c);
      const char* kind = std::isnan(data[i]) ? "NaN" : "infinite";
      std::free(data);
      return report(kIsochartsImageInputError,
                    "pixel (" + std::to_string(texel % spec.width) + "," + std::to_string(texel / spec.width) +
                        ") " + channel + " is " + kind + " (" +
                        std::to_string(bad) + " value" + (bad == 1 ? "" : "s") + " not finite)",
                    message, message_size);
    }
  std::string joined;
  for (int c = 0; c < spec.nchannels; ++c)
    joined += (c < static_cast<int>(spec.channelnames.size()) ? spec.channelnames[c] : std::string()) + "\n";
  report(0, joined, names, names_size);
  *width = spec.width;
  *height = spec.height;
  *channels = spec.nchannels;
  // What the file can say: a 16-bit texture carried through an atlas should stay 16-bit.
  const OIIO::TypeDesc::BASETYPE base = static_cast<OIIO::TypeDesc::BASETYPE>(spec.format.basetype);
  const bool floating =
      base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::DOUBLE;
  *bits = floating ? 32 : spec.format.size() >= 2 ? 16 : 8;
  *pixels = data;
  return kIsochartsImageOk;
}

// Writes `bytes` to `path`, every call checked. 0 or errno.
int write_bytes(const char* path, const std::vector<unsigned char>& bytes) {
  std::FILE* f = std::fopen(path, "wb");
  if (!f) return errno ? errno : EIO;
  int err = 0;
  if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) err = errno ? errno : EIO;
  if (std::fflush(f) != 0 && !err) err = errno ? errno : EIO;
  if (std::fclose(f) != 0 && !err) err = errno ? errno : EIO;
  return err;
}

int write_file(const char* path, int width, int height, int channels, int stride, const float* pixels,
               int bits, int alpha, const char* names, const char* const* attributes, char* message,
               std::size_t message_size) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) {
    OIIO::geterror();  // names the file; the caller's message names the format
    return report(kIsochartsImageUnsupported, "unsupported image format", message, message_size);
  }
  // PNG and JPEG are encoded into memory and written here: on a failed write (a full disk)
  // libjpeg's error handler prints its own line and exits the process, and libpng drops the
  // error and reports success with the file cut short. Both are small next to their pixels.
  const int complete_check = trailer_complete(path, false);
  std::vector<unsigned char> encoded;
  OIIO::Filesystem::IOVecOutput memory(encoded);
  const bool in_memory = complete_check >= 0 && out->supports("ioproxy") && out->set_ioproxy(&memory);
  const OIIO::TypeDesc type = bits == 32   ? OIIO::TypeDesc::FLOAT
                              : bits == 16 ? OIIO::TypeDesc::UINT16
                                           : OIIO::TypeDesc::UINT8;
  OIIO::ImageSpec spec(width, height, channels, type);
  spec.alpha_channel = alpha;
  // Our pixels have straight alpha; without this the writer would divide colours by alpha.
  if (alpha >= 0) spec.attribute("oiio:UnassociatedAlpha", 1);
  if (names) {
    spec.channelnames.clear();
    for (const char* p = names; *p;) {
      const char* end = std::strchr(p, '\n');
      if (!end) end = p + std::strlen(p);
      spec.channelnames.emplace_back(p, end);
      p = *end ? end + 1 : end;
    }
    spec.channelnames.resize(channels);
  }
  if (attributes)
    for (const char* const* a = attributes; a[0] && a[1]; a += 2) spec.attribute(a[0], a[1]);
  if (!spec.find_attribute("DateTime")) spec.attribute("DateTime", "");
  auto fail = [&](const std::string& detail, int status = kIsochartsImageError) {
    out.reset();
    std::remove(path);
    OIIO::geterror();
    return report(status, one_line(detail), message, message_size);
  };
  // Refused before a byte is written: the format cannot hold this image (PNM and 4 channels,
  // ICO beyond 256x256). The directory was checked writable before the run: a usage error.
  if (!out->open(path, spec)) return fail(out->geterror(), kIsochartsImageInputError);
  const auto xstride = static_cast<OIIO::stride_t>(sizeof(float)) * stride;
  if (!out->write_image(OIIO::TypeDesc::FLOAT, pixels, xstride)) return fail(out->geterror());
  if (!out->close()) return fail(out->geterror());
  out.reset();
  if (in_memory) {
    const int err = write_bytes(path, encoded);
    if (err) return fail(std::strerror(err));
    return kIsochartsImageOk;
  }
  // Some writers (PNG among them) drop the errors of their last writes, e.g. on a full disk, and
  // report success with the file cut short: check its end marker. Other formats' writers
  // (OpenEXR, TIFF) report write errors themselves; their header is re-read as a cheap check,
  // not the pixels (a large EXR would cost its whole size in memory again).
  const int complete = trailer_complete(path, false);
  bool whole = complete == 1;
  if (complete < 0) {
    auto in = OIIO::ImageInput::open(path);
    // Only the size: some formats read back with other channels than written (GIF as RGBA).
    whole = in && in->spec().width == width && in->spec().height == height;
    if (in) in->close();
    OIIO::geterror();
  }
  if (!whole) return fail("the written file is cut short, disk full?");
  return kIsochartsImageOk;
}

// libpng's default error handler, which OIIO's PNG reader keeps, prints "libpng error: ..."
// on stderr before OIIO reports the same problem to us; the user gets our one line only. The
// reader's own stderr output is sent to /dev/null while it runs (a progress line printed by
// another thread meanwhile is lost, nothing else writes to stderr during a read).
class QuietStderr {
 public:
  QuietStderr() {
    std::fflush(stderr);
    saved_ = ::dup(STDERR_FILENO);
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ >= 0 && null >= 0) ::dup2(null, STDERR_FILENO);
    if (null >= 0) ::close(null);
  }
  ~QuietStderr() {
    std::fflush(stderr);
    if (saved_ >= 0) {
      ::dup2(saved_, STDERR_FILENO);
      ::close(saved_);
    }
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  int saved_ = -1;
};

// Nothing may escape across the C boundary.
int safe_read(const char* path, long long max_values, int* width, int* height, int* channels, int* bits,
              float** pixels, char* names, std::size_t names_size, char* message, std::size_t message_size) {
  try {
    const QuietStderr quiet;
    return read_file(path, max_values, width, height, channels, bits, pixels, names, names_size, message,
                     message_size);
  } catch (const std::bad_alloc&) {
    return report(kIsochartsImageError, "out of memory reading the image", message, message_size);
  } catch (const std::exception& e) {
    return report(kIsochartsImageInputError, with_detail("cannot read image", e.what()), message,
                  message_size);
  }
}

int safe_write(const char* path, int width, int height, int channels, int stride, const float* pixels,
               int bits, int alpha, const char* names, const char* const* attributes, char* message,
               std::size_t message_size) {
  try {
    return write_file(path, width, height, channels, stride, pixels, bits, alpha, names, attributes, message,
                      message_size);
  } catch (const std::exception& e) {
    std::remove(path);
    return report(kIsochartsImageError, one_line(e.what()), message, message_size);
  }
}

void free_pixels(float* p) {
  std::free(p);
}

int can_write(const char* path) {
  try {
    // create() only picks the plugin for the extension; nothing is opened.
    const bool ok = OIIO::ImageOutput::create(path) != nullptr;
    if (!ok) OIIO::geterror();
    return ok ? 1 : 0;
  } catch (const std::exception&) {
    return 0;
  }
}

const IsochartsImageModule kModule = {ISOCHARTS_IMAGE_MODULE_ABI, safe_read, free_pixels, safe_write,
                                      can_write};

}  // namespace

extern "C" __attribute__((visibility("default"))) const IsochartsImageModule* isocharts_image_module() {
  return &kModule;
}
