// SPDX-License-Identifier: BSD-3-Clause
// 8-bit RGB PNG files through libpng. Errors throw IoError / FormatError naming the path.
#pragma once

#include <string>

#include "afam/render/image.hpp"

namespace afam {

/// Writes PATH atomically (PATH.tmp then rename): no half file is left on failure.
void writePng(const std::string& path, const ImageRGB8& image);
/// Reads any 8/16-bit PNG (grey, RGB, palette, with or without alpha) as 8-bit RGB; alpha dropped.
ImageRGB8 readPng(const std::string& path);

}  // namespace afam
