#include "src/render/image.hpp"

#include <gtest/gtest.h>

#include <random>

namespace sd::render {
namespace {

TEST(Image, ParsesSizes) {
  EXPECT_EQ(parse_image_size("800x1200"), (ImageSize{800, 1200}));
  EXPECT_EQ(parse_image_size("1X1"), (ImageSize{1, 1}));
  for (const char* bad :
       {"", "800", "800x", "x600", "0x10", "-5x10", "10x10x10", "4097x10", "ax b", "80 0x10"})
    EXPECT_THROW(parse_image_size(bad), ImageSizeError) << bad;
}

TEST(Image, PngRoundTripIsExact) {
  Image image(37, 23);  // odd sizes catch row-stride mistakes
  std::mt19937 rng(7);
  for (auto& byte : image.rgba) byte = static_cast<std::uint8_t>(rng());
  const std::string png = encode_png(image);
  ASSERT_GE(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  const Image back = decode_png(png);
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 23);
  EXPECT_EQ(back.rgba, image.rgba);
}

TEST(Image, RowsAreStoredTopToBottom) {
  Image image(2, 2);
  image.pixel(1, 0)[0] = 200;  // top right
  EXPECT_EQ(image.rgba[4], 200);
}

TEST(Image, DecodeRejectsGarbage) {
  EXPECT_THROW(decode_png("not a png at all"), PngError);
  Image image(4, 4);
  std::string png = encode_png(image);
  png.resize(png.size() / 2);  // truncated
  EXPECT_THROW(decode_png(png), PngError);
}

}  // namespace
}  // namespace sd::render
