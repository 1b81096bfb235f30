#include "src/render/image.hpp"

#include <fmt/format.h>
#include <png.h>

#include <charconv>
#include <cstring>
#include <memory>

namespace sd::render {
namespace {

int parse_side(std::string_view text, std::string_view whole) {
  int value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc{} || end != text.data() + text.size() || value < 1 ||
      value > kMaxImageSide)
    throw ImageSizeError(fmt::format(
        "image size '{}' is not valid: write WIDTHxHEIGHT in pixels, each from 1 to {}, e.g. "
        "800x1200",
        whole, kMaxImageSide));
  return value;
}

void append_to_string(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::string*>(png_get_io_ptr(png));
  out->append(reinterpret_cast<const char*>(data), length);
}

void flush_nothing(png_structp) {}

// libpng's default handlers print to stderr; these keep the message for the exception instead.
[[noreturn]] void keep_error(png_structp png, png_const_charp message) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = message;
  png_longjmp(png, 1);
}
void ignore_warning(png_structp, png_const_charp) {}

struct ReadCursor {
  std::string_view bytes;
  size_t offset = 0;
};

void read_from_view(png_structp png, png_bytep data, png_size_t length) {
  auto* cursor = static_cast<ReadCursor*>(png_get_io_ptr(png));
  if (cursor->offset + length > cursor->bytes.size()) png_error(png, "PNG data ends early");
  std::memcpy(data, cursor->bytes.data() + cursor->offset, length);
  cursor->offset += length;
}

}  // namespace

ImageSize parse_image_size(std::string_view text) {
  const size_t x = text.find_first_of("xX");
  if (x == std::string_view::npos)
    throw ImageSizeError(fmt::format(
        "image size '{}' is not valid: write WIDTHxHEIGHT in pixels, e.g. 800x1200", text));
  return {parse_side(text.substr(0, x), text), parse_side(text.substr(x + 1), text)};
}

Image::Image(int w, int h) : width(w), height(h), rgba(static_cast<size_t>(w) * h * 4, 0) {}

// libpng reports errors through longjmp. Everything written between setjmp and a possible jump
// lives on the heap behind a pointer that is not changed after setjmp, so no local is left
// indeterminate by the jump (C++ [csetjmp.syn], C 7.13.2.1).
std::string encode_png(const Image& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgba.size() != static_cast<size_t>(image.width) * image.height * 4)
    throw std::invalid_argument("encode_png: image buffer does not match its size");
  auto out = std::make_unique<std::string>();
  auto error = std::make_unique<std::string>();
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, error.get(), keep_error, ignore_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error("libpng could not allocate an encoder");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error("libpng failed to encode the image: " + *error);
  }
  png_set_write_fn(png, out.get(), append_to_string, flush_nothing);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
               static_cast<png_uint_32>(image.height), 8, PNG_COLOR_TYPE_RGB_ALPHA,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  // Level 3 with the "up"/"sub" filters: most of the size gain of level 9 at a fraction of the
  // time on smooth renders (see docs/rendering.md).
  png_set_compression_level(png, 3);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB | PNG_FILTER_UP);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y)
    png_write_row(png, const_cast<png_bytep>(image.pixel(0, y)));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return std::move(*out);
}

Image decode_png(std::string_view bytes) {
  if (bytes.size() < 8 || png_sig_cmp(reinterpret_cast<png_const_bytep>(bytes.data()), 0, 8) != 0)
    throw PngError("the data is not a PNG image");
  auto error = std::make_unique<std::string>();
  png_structp png =
      png_create_read_struct(PNG_LIBPNG_VER_STRING, error.get(), keep_error, ignore_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw PngError("libpng could not allocate a decoder");
  }
  auto image = std::make_unique<Image>();
  auto cursor = std::make_unique<ReadCursor>(ReadCursor{bytes, 0});
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw PngError("the PNG image is corrupt: " + *error);
  }
  png_set_read_fn(png, cursor.get(), read_from_view);
  png_read_info(png, info);
  // Normalise every PNG flavour to 8-bit RGBA.
  png_set_expand(png);
  png_set_strip_16(png);
  png_set_gray_to_rgb(png);
  png_set_add_alpha(png, 0xff, PNG_FILLER_AFTER);
  png_read_update_info(png, info);
  *image = Image(static_cast<int>(png_get_image_width(png, info)),
                 static_cast<int>(png_get_image_height(png, info)));
  for (int y = 0; y < image->height; ++y) png_read_row(png, image->pixel(0, y), nullptr);
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return std::move(*image);
}

}  // namespace sd::render
