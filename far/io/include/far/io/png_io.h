#pragma once

// PNG files of 8-bit RGB pictures (far-snapshot), through libpng.

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "far/base/result.h"

namespace far {

/// An 8-bit RGB picture as read from a PNG file, rows from top to bottom.
struct PngImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  ///< width * height * 3 bytes
};

/// Writes `rgb` (width * height * 3 bytes, rows from top to bottom) as an 8-bit RGB PNG file.
/// Errors: kInvalidArgument for sizes that do not match, kIoError (libpng's message) when the
/// file cannot be written.
Result<void> WritePng(const std::filesystem::path& path, int width, int height,
                      std::span<const uint8_t> rgb);

/// Reads any PNG file libpng reads, converted to 8-bit RGB (alpha composited on black).
/// Errors: kIoError when the file cannot be read, kParseError when it is not a valid PNG.
Result<PngImage> ReadPng(const std::filesystem::path& path);

}  // namespace far
