#pragma once
// Rendered images and their PNG encoding. The renderer never writes files: callers get PNG bytes
// and write them through the app's atomic output (src/app/pipeline/atomic_file.hpp).

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace sd::render {

// A size the user asked for that cannot be rendered ("800x", "0x100", "99999x10").
class ImageSizeError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// A PNG that cannot be decoded (corrupt or not a PNG).
class PngError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ImageSize {
  int width = 0;   // pixels
  int height = 0;  // pixels
  double aspect() const { return static_cast<double>(width) / height; }
  bool operator==(const ImageSize&) const = default;
};

// Largest side accepted, in pixels: a 4096x4096 frame with 4 samples of colour + depth per pixel
// takes 0.5 GB (llvmpipe's own limit is 16384, but that would be 8 GB).
inline constexpr int kMaxImageSide = 4096;

// Parses "WxH" (e.g. "800x1200"); both sides in [1, kMaxImageSide]. Throws ImageSizeError.
ImageSize parse_image_size(std::string_view text);

// 8-bit RGBA, rows stored top to bottom, `width * height * 4` bytes, not premultiplied.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;

  Image() = default;
  Image(int width, int height);  // filled with zeros

  ImageSize size() const { return {width, height}; }
  std::uint8_t* pixel(int x, int y) { return &rgba[4 * (static_cast<size_t>(y) * width + x)]; }
  const std::uint8_t* pixel(int x, int y) const {
    return &rgba[4 * (static_cast<size_t>(y) * width + x)];
  }
};

// Encodes `image` as an 8-bit RGBA PNG and returns the file's bytes.
std::string encode_png(const Image& image);

// Decodes PNG bytes (any bit depth / colour type) into 8-bit RGBA. Throws PngError.
Image decode_png(std::string_view bytes);

}  // namespace sd::render
