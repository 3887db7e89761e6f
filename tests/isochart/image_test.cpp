#include "isochart/image.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "isochart/error.h"

using namespace isochart;
namespace fs = std::filesystem;

namespace {

// A fresh, empty directory per test case, removed afterwards.
struct TempDir {
  fs::path path;
  TempDir() {
    static int counter = 0;
    path = fs::temp_directory_path() /
           ("isocharts_image_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string file(const std::string& name) const { return (path / name).string(); }
  int entries() const {
    return static_cast<int>(std::distance(fs::directory_iterator(path), fs::directory_iterator()));
  }
};

// Values on the 8-bit grid (k/255) so a PNG round trip is exact.
Image gradient_image(int w, int h, int c) {
  Image img(w, h, c);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < c; ++k)
        img.at(x, y, k) = static_cast<float>(((x * 37 + y * 11 + k * 85) % 256) / 255.0);
  return img;
}

// The bytes of a PNG that declares w × h grey pixels and holds none (only its header is
// read before the size check).
std::string png_header_only(std::uint32_t w, std::uint32_t h) {
  auto crc32 = [](const std::string& bytes) {
    std::uint32_t c = 0xffffffffu;
    for (unsigned char b : bytes) {
      c ^= b;
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return c ^ 0xffffffffu;
  };
  auto be32 = [](std::uint32_t v) {
    return std::string{static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
                       static_cast<char>(v)};
  };
  auto chunk = [&](const std::string& type, const std::string& data) {
    return be32(static_cast<std::uint32_t>(data.size())) + type + data + be32(crc32(type + data));
  };
  const std::string ihdr = be32(w) + be32(h) + std::string("\x08\x00\x00\x00\x00", 5);
  return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + chunk("IDAT", "") + chunk("IEND", "");
}

}  // namespace

TEST_CASE("an image whose pixels would not fit in memory is refused from its header", "[image]") {
  TempDir dir;
  // 9000² grey is 81 M pixels, read as four floats each: over the limit of 8192².
  const std::string path = dir.file("huge_grey.png");
  std::ofstream(path, std::ios::binary) << png_header_only(9000, 9000);
  CHECK_THROWS_WITH(read_image(path), Catch::Contains("image too large (9000x9000 pixels"));
}

TEST_CASE("images are told by their first bytes: an empty file says so, a PNG named .jpg reads", "[image]") {
  TempDir dir;
  const std::string empty = dir.file("empty.png");
  std::ofstream(empty).close();
  CHECK_THROWS_WITH(read_image(empty), Catch::Contains("the file is empty"));
  const Image img = gradient_image(7, 5, 3);
  write_image(dir.file("real.png"), img);
  fs::copy_file(dir.file("real.png"), dir.file("named.jpg"));
  const Image back = read_image(dir.file("named.jpg"));
  CHECK(back.width == 7);
  CHECK(back.pixels == read_image(dir.file("real.png")).pixels);
  // Cut short, it is still known for a PNG by its first bytes.
  fs::resize_file(dir.file("named.jpg"), fs::file_size(dir.file("named.jpg")) - 12);
  CHECK_THROWS_WITH(read_image(dir.file("named.jpg")), Catch::Contains("cut short"));
  // A device or a pipe is refused: the image library read /dev/zero without end.
  fs::create_symlink("/dev/zero", dir.file("zero.png"));
  CHECK_THROWS_WITH(read_image(dir.file("zero.png")), Catch::Contains("is not a regular file"));
  REQUIRE(::mkfifo(dir.file("pipe.exr").c_str(), 0600) == 0);
  CHECK_THROWS_WITH(read_image(dir.file("pipe.exr")), Catch::Contains("is not a regular file"));
}

TEST_CASE("resize_area averages the texels each new texel covers", "[image]") {
  Image img(4, 2, 1);
  for (int x = 0; x < 4; ++x) img.at(x, 0, 0) = img.at(x, 1, 0) = static_cast<float>(x);
  const Image half = resize_area(img, 2, 1);
  CHECK(half.at(0, 0, 0) == Approx(0.5));
  CHECK(half.at(1, 0, 0) == Approx(2.5));
  // Three texels into two: the middle one is shared half and half.
  Image three(3, 1, 1);
  three.at(0, 0, 0) = 0;
  three.at(1, 0, 0) = 3;
  three.at(2, 0, 0) = 6;
  const Image two = resize_area(three, 2, 1);
  CHECK(two.at(0, 0, 0) == Approx((0 * 1.0 + 3 * 0.5) / 1.5));
  CHECK(two.at(1, 0, 0) == Approx((3 * 0.5 + 6 * 1.0) / 1.5));
}

TEST_CASE("fill_from_nearest spreads the nearest filled texel, keeping one channel", "[image]") {
  Image img(4, 1, 2, 0.0f);
  img.at(0, 0, 0) = 0.75f;
  img.at(0, 0, 1) = 1.0f;
  std::vector<char> filled{1, 0, 0, 0};
  fill_from_nearest(img, filled, 1);
  for (int x = 1; x < 4; ++x) {
    CHECK(img.at(x, 0, 0) == 0.75f);
    CHECK(img.at(x, 0, 1) == 0.0f);  // kept
  }
  CHECK(std::all_of(filled.begin(), filled.end(), [](char f) { return f == 1; }));
}

TEST_CASE("PNG round trip keeps size, channels and 8-bit values", "[image]") {
  TempDir dir;
  for (int channels : {1, 3, 4}) {
    const Image a = gradient_image(7, 5, channels);
    const std::string path = dir.file("rgb" + std::to_string(channels) + ".png");
    write_image(path, a);
    const Image b = read_image(path);
    REQUIRE(b.width == 7);
    REQUIRE(b.height == 5);
    REQUIRE(b.channels == channels);
    double worst = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
      worst = std::max(worst, double(std::abs(a.pixels[i] - b.pixels[i])));
    CHECK(worst < 1e-6);
    // Rows are stored top first: pixel (6, 0) keeps its value.
    CHECK(b.at(6, 0, 0) == Approx(a.at(6, 0, 0)).margin(1e-6));
  }
}

TEST_CASE("a 16-bit image stays 16-bit where the format holds it", "[image]") {
  TempDir dir;
  Image a(4, 2, 3);
  for (std::size_t i = 0; i < a.pixels.size(); ++i) a.pixels[i] = static_cast<float>(1000 + 37 * i) / 65535;
  CHECK(a.bits == 8);
  write_image(dir.file("eight.png"), a);
  const Image eight = read_image(dir.file("eight.png"));
  CHECK(eight.bits == 8);
  CHECK(std::abs(eight.pixels[0] - a.pixels[0]) > 1e-4);  // 1000/65535 is 4.3e-4 from 4/255
  a.bits = 16;
  for (const std::string ext : {".png", ".tif"}) {
    INFO(ext);
    write_image(dir.file("deep" + ext), a);
    const Image b = read_image(dir.file("deep" + ext));
    CHECK(b.bits == 16);
    double worst = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
      worst = std::max(worst, double(std::abs(a.pixels[i] - b.pixels[i])));
    CHECK(worst < 1e-6);
  }
  write_image(dir.file("deep.jpg"), a);
  CHECK(read_image(dir.file("deep.jpg")).bits == 8);
  write_image(dir.file("deep.exr"), a);
  CHECK(read_image(dir.file("deep.exr")).bits == 32);
}

TEST_CASE("8-bit output clamps and rounds", "[image]") {
  TempDir dir;
  Image a(3, 1, 1);
  a.pixels = {-0.5f, 0.5f, 2.0f};
  write_image(dir.file("c.png"), a);
  const Image b = read_image(dir.file("c.png"));
  CHECK(b.pixels[0] == 0.0f);
  CHECK(std::abs(b.pixels[1] - 128 / 255.0f) < 1.0f / 255);
  CHECK(b.pixels[2] == 1.0f);
}

TEST_CASE("EXR round trip keeps float values exactly", "[image]") {
  TempDir dir;
  Image a(4, 3, 3);
  for (std::size_t i = 0; i < a.pixels.size(); ++i) a.pixels[i] = static_cast<float>(-2.5 + 0.3137 * i);
  write_image(dir.file("geo.exr"), a);
  const Image b = read_image(dir.file("geo.exr"));
  REQUIRE(b.width == 4);
  REQUIRE(b.height == 3);
  REQUIRE(b.channels == 3);
  CHECK(a.pixels == b.pixels);
  // No capture date: the same image gives the same bytes at any time (OpenImageIO would stamp
  // the current time into the header's capDate).
  std::ifstream in(dir.file("geo.exr"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string stamp("capDate\0string\0", 15);
  const std::size_t at = bytes.find(stamp);
  if (at != std::string::npos) CHECK(bytes.substr(at + stamp.size(), 4) == std::string(4, '\0'));
}

TEST_CASE("an EXR with a NaN or infinite value is refused, naming the pixel", "[image]") {
  TempDir dir;
  Image a(4, 3, 3);
  for (std::size_t i = 0; i < a.pixels.size(); ++i) a.pixels[i] = 0.25f;
  a.at(2, 1, 1) = std::numeric_limits<float>::quiet_NaN();
  a.at(3, 2, 0) = std::numeric_limits<float>::infinity();
  write_image(dir.file("nan.exr"), a);
  CHECK_THROWS_WITH(read_image(dir.file("nan.exr")), Catch::Contains("pixel (2,1) G is NaN (2 values not finite)"));
  a.at(2, 1, 1) = 0.5f;
  write_image(dir.file("inf.exr"), a);
  CHECK_THROWS_WITH(read_image(dir.file("inf.exr")), Catch::Contains("pixel (3,2) R is infinite (1 value not finite)"));
}

TEST_CASE("named channels and attributes reach the file", "[image]") {
  TempDir dir;
  Image a(3, 2, 5);
  for (std::size_t i = 0; i < a.pixels.size(); ++i) a.pixels[i] = static_cast<float>(i) - 4.0f;
  a.channel_names = {"R", "G", "B", "mask", "id"};
  a.attributes = {{"compression", "zip"}, {"isocharts:kind", "test"}};
  write_image(dir.file("named.exr"), a);
  const Image b = read_image(dir.file("named.exr"));
  REQUIRE(b.channels == 5);
  REQUIRE(b.channel_names.size() == 5);
  // EXR stores channels sorted by name; every value must come back under its own name.
  for (int c = 0; c < 5; ++c) {
    const auto it = std::find(b.channel_names.begin(), b.channel_names.end(), a.channel_names[c]);
    REQUIRE(it != b.channel_names.end());
    const int bc = static_cast<int>(it - b.channel_names.begin());
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 3; ++x) CHECK(b.at(x, y, bc) == a.at(x, y, c));
  }
  CHECK(dir.entries() == 1);
}

TEST_CASE("JPEG output drops alpha", "[image]") {
  TempDir dir;
  Image a(8, 8, 4, 0.5f);
  write_image(dir.file("a.jpg"), a);
  const Image b = read_image(dir.file("a.jpg"));
  CHECK(b.channels == 3);
  CHECK(std::abs(b.at(3, 3, 0) - 0.5f) < 0.02f);
}

TEST_CASE("PGM output is grey, PBM is refused", "[image]") {
  // The PNM writer put colour (P6) into a file named .pgm.
  TempDir dir;
  Image a(4, 2, 4, 1.0f);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) {
      a.at(x, y, 0) = 1.0f;  // red
      a.at(x, y, 1) = 0.0f;
      a.at(x, y, 2) = 0.0f;
    }
  write_image(dir.file("a.pgm"), a);
  std::ifstream in(dir.file("a.pgm"), std::ios::binary);
  std::string magic(2, ' ');
  in.read(&magic[0], 2);
  CHECK(magic == "P5");
  const Image b = read_image(dir.file("a.pgm"));
  CHECK(b.channels == 1);
  CHECK(std::abs(b.at(1, 1, 0) - 0.2126f) < 0.01f);
  CHECK_THROWS_WITH(check_image_output(dir.file("a.pbm")), Catch::Contains("PBM holds black and white only"));
  CHECK_THROWS_WITH(write_image(dir.file("a.pbm"), a), Catch::Contains("PBM holds black and white only"));
  CHECK(dir.entries() == 1);
}

TEST_CASE("formats that read back with other channels are written without a false error", "[image]") {
  // GIF comes back as RGBA; the write check compares the size only ("cut short, disk full?"
  // was reported for every GIF).
  TempDir dir;
  write_image(dir.file("a.gif"), Image(8, 6, 3, 0.5f));
  const Image b = read_image(dir.file("a.gif"));
  CHECK(b.width == 8);
  CHECK(b.height == 6);
}

TEST_CASE("write_image is atomic and leaves no temporary files", "[image]") {
  TempDir dir;
  const std::string path = dir.file("out.png");
  write_image(path, gradient_image(4, 4, 3));
  CHECK(dir.entries() == 1);
  // Overwriting replaces the file in one step.
  write_image(path, gradient_image(9, 2, 3));
  CHECK(read_image(path).width == 9);
  CHECK(dir.entries() == 1);
}

TEST_CASE("write_image errors", "[image]") {
  TempDir dir;
  const Image img = gradient_image(2, 2, 3);
  SECTION("missing directory") {
    const std::string path = dir.file("no/such/dir/x.png");
    CHECK_THROWS_AS(write_image(path, img), InputError);
    CHECK(dir.entries() == 0);
  }
  SECTION("a format that cannot hold the image: the input's fault, nothing left") {
    // PNM has no alpha: refused by the writer before a byte is written (it was exit 1).
    CHECK_THROWS_WITH(write_image(dir.file("x.ppm"), gradient_image(2, 2, 4)),
                      Catch::Contains("cannot write this image in that format"));
    CHECK_THROWS_AS(write_image(dir.file("x.ppm"), gradient_image(2, 2, 4)), InputError);
    CHECK(dir.entries() == 0);
  }
  SECTION("unknown extension") {
    CHECK_THROWS_AS(write_image(dir.file("x.notanimage"), img), InputError);
    CHECK_THROWS_AS(write_image(dir.file("noextension"), img), InputError);
    CHECK(dir.entries() == 0);
  }
  SECTION("inconsistent image") {
    Image bad(2, 2, 3);
    bad.pixels.pop_back();
    CHECK_THROWS_AS(write_image(dir.file("x.png"), bad), Error);
    CHECK(dir.entries() == 0);
  }
}

TEST_CASE("read_image errors name the file", "[image]") {
  TempDir dir;
  SECTION("missing file") {
    const std::string path = dir.file("missing.png");
    try {
      read_image(path);
      FAIL("no exception");
    } catch (const InputError& e) {
      CHECK(e.file() == path);
      CHECK(std::string(e.what()).find("not found") != std::string::npos);
    }
  }
  SECTION("not an image") {
    const std::string path = dir.file("garbage.png");
    std::ofstream(path) << "this is not a PNG file\n";
    try {
      read_image(path);
      FAIL("no exception");
    } catch (const InputError& e) {
      CHECK(e.file() == path);
      CHECK(std::string(e.what()).find('\n') == std::string::npos);
    }
  }
  SECTION("truncated image") {
    const std::string path = dir.file("big.png");
    Image img(64, 64, 3);
    for (std::size_t i = 0; i < img.pixels.size(); ++i)
      img.pixels[i] = static_cast<float>((i * 7919) % 256) / 255;
    write_image(path, img);
    fs::resize_file(path, fs::file_size(path) / 2);
    CHECK_THROWS_AS(read_image(path), InputError);
  }
  SECTION("directory") {
    CHECK_THROWS_AS(read_image(dir.path.string()), InputError);
  }
}

TEST_CASE("bilinear lookup far outside the image reads its period or border, never NaN", "[image]") {
  // A material scaling its coordinates by 1e300 overflowed u · width and drew black (NaN).
  Image img(2, 2, 1);
  img.at(0, 0, 0) = 0.0f;
  img.at(1, 0, 0) = 1.0f;
  img.at(0, 1, 0) = 2.0f;
  img.at(1, 1, 0) = 3.0f;
  float far = -1, near = -1;
  for (const Wrap w : {Wrap::Clamp, Wrap::Repeat, Wrap::Mirror}) {
    for (const double u : {1e300, -1e300, 1.7e308, 3e7}) {
      sample_bilinear(img, u, 0.25, &far, w, w);
      CHECK(std::isfinite(far));
    }
  }
  sample_bilinear(img, 1e300, 0.25, &far, Wrap::Clamp, Wrap::Clamp);
  sample_bilinear(img, 2.0, 0.25, &near, Wrap::Clamp, Wrap::Clamp);
  CHECK(far == near);  // the right border
  sample_bilinear(img, 1e300 + 0.25, 0.25, &far, Wrap::Repeat, Wrap::Repeat);
  sample_bilinear(img, 0.0, 0.25, &near, Wrap::Repeat, Wrap::Repeat);
  CHECK(far == near);  // 1e300 is a whole number of periods (its fraction is below precision)
}

TEST_CASE("bilinear lookup", "[image]") {
  // 2×2 grey image; rows top first, so v = 1 is the top row.
  Image img(2, 2, 1);
  img.at(0, 0, 0) = 0.0f;  // top left
  img.at(1, 0, 0) = 1.0f;  // top right
  img.at(0, 1, 0) = 2.0f;  // bottom left
  img.at(1, 1, 0) = 3.0f;  // bottom right
  float v = -1;
  sample_bilinear(img, 0.5, 0.5, &v);
  CHECK(v == Approx(1.5));
  sample_bilinear(img, 0.25, 0.75, &v);  // top-left texel centre
  CHECK(v == Approx(0.0));
  sample_bilinear(img, 0.75, 0.25, &v);  // bottom-right texel centre
  CHECK(v == Approx(3.0));
  sample_bilinear(img, -5.0, 0.25, &v, Wrap::Clamp);
  CHECK(v == Approx(2.0));
  sample_bilinear(img, 1.25, 0.25, &v, Wrap::Repeat);  // same as u = 0.25
  CHECK(v == Approx(2.0));
  // Mirrored: the tile right of [0, 1] is the texture flipped, so u = 1.25 reads u = 0.75,
  // and the next tile is the texture again (u = 2.25 reads u = 0.25).
  sample_bilinear(img, 1.25, 0.25, &v, Wrap::Mirror);
  CHECK(v == Approx(3.0));
  sample_bilinear(img, 2.25, 0.25, &v, Wrap::Mirror);
  CHECK(v == Approx(2.0));
  sample_bilinear(img, -0.25, 0.25, &v, Wrap::Mirror);  // flipped left of 0 too: u = 0.25
  CHECK(v == Approx(2.0));
  sample_bilinear(img, 1.0, 0.25, &v, Wrap::Mirror);  // the seam blends a texel with itself
  CHECK(v == Approx(3.0));
  // Each axis its own way: u repeats, v is clamped (and the other way round).
  sample_bilinear(img, 1.25, 7.0, &v, Wrap::Repeat, Wrap::Clamp);  // u = 0.25, top row
  CHECK(v == Approx(0.0));
  sample_bilinear(img, 7.0, 1.25, &v, Wrap::Clamp, Wrap::Repeat);  // right column, v = 0.25
  CHECK(v == Approx(3.0));
  sample_bilinear(img, 0.25, 1.25, &v, Wrap::Clamp, Wrap::Mirror);  // v = 0.75: top row
  CHECK(v == Approx(0.0));
}
