// SPDX-License-Identifier: BSD-3-Clause
#include "afam/eval/png_io.hpp"

#include <png.h>

#include <cstdio>
#include <memory>
#include <vector>

#include "afam/base/errors.hpp"

namespace afam {
namespace {

struct FileCloser {
  void operator()(FILE* f) const {
    if (f) std::fclose(f);
  }
};

}  // namespace

void writePng(const std::string& path, const ImageRGB8& im) {
  if (im.width < 1 || im.height < 1 || im.rgb.size() != size_t(im.width) * im.height * 3)
    throw InvalidArgument("png " + path + ": image is empty or its buffer has the wrong size");
  const std::string tmp = path + ".tmp";
  FILE* raw = std::fopen(tmp.c_str(), "wb");
  if (!raw) throw IoError("png " + path + ": cannot open " + tmp + " for writing");
  std::unique_ptr<FILE, FileCloser> f(raw);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    std::remove(tmp.c_str());
    throw IoError("png " + path + ": libpng initialisation failed");
  }
  std::vector<png_bytep> rows(size_t(im.height));
  for (int y = 0; y < im.height; ++y)
    rows[size_t(y)] = const_cast<png_bytep>(&im.rgb[size_t(y) * im.width * 3]);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    f.reset();
    std::remove(tmp.c_str());
    throw IoError("png " + path + ": write failed");
  }
  png_init_io(png, f.get());
  png_set_IHDR(png, info, png_uint_32(im.width), png_uint_32(im.height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(f.release()) != 0) {
    std::remove(tmp.c_str());
    throw IoError("png " + path + ": close failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw IoError("png " + path + ": cannot rename " + tmp);
  }
}

ImageRGB8 readPng(const std::string& path) {
  FILE* raw = std::fopen(path.c_str(), "rb");
  if (!raw) throw IoError("png " + path + ": cannot open");
  std::unique_ptr<FILE, FileCloser> f(raw);
  unsigned char sig[8];
  if (std::fread(sig, 1, 8, f.get()) != 8 || png_sig_cmp(sig, 0, 8) != 0)
    throw FormatError("png " + path + ": not a PNG file");
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw IoError("png " + path + ": libpng initialisation failed");
  }
  ImageRGB8 im;
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw FormatError("png " + path + ": damaged PNG");
  }
  png_init_io(png, f.get());
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  const png_byte type = png_get_color_type(png, info);
  if (png_get_bit_depth(png, info) == 16) png_set_strip_16(png);
  if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (type == PNG_COLOR_TYPE_GRAY || type == PNG_COLOR_TYPE_GRAY_ALPHA) {
    if (png_get_bit_depth(png, info) < 8) png_set_expand_gray_1_2_4_to_8(png);
    png_set_gray_to_rgb(png);
  }
  if (type & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_strip_alpha(png);
  png_read_update_info(png, info);
  im.width = int(png_get_image_width(png, info));
  im.height = int(png_get_image_height(png, info));
  if (png_get_rowbytes(png, info) != size_t(im.width) * 3) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw FormatError("png " + path + ": unsupported pixel layout");
  }
  im.rgb.resize(size_t(im.width) * im.height * 3);
  rows.resize(size_t(im.height));
  for (int y = 0; y < im.height; ++y) rows[size_t(y)] = &im.rgb[size_t(y) * im.width * 3];
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return im;
}

}  // namespace afam
