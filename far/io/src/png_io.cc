// PNG through libpng's simplified API (png_image), which does the format's work: filtering,
// compression, conversion of whatever a file holds to 8-bit RGB.

#include "far/io/png_io.h"

#include <png.h>

#include <string>

#include "io_util.h"

namespace far {

Result<void> WritePng(const std::filesystem::path& path, int width, int height,
                      std::span<const uint8_t> rgb) {
  if (width <= 0 || height <= 0 ||
      rgb.size() != static_cast<size_t>(width) * static_cast<size_t>(height) * 3) {
    return MakeError(ErrorCode::kInvalidArgument,
                     path.string() + ": " + std::to_string(rgb.size()) + " bytes are not a " +
                         std::to_string(width) + "x" + std::to_string(height) + " RGB picture");
  }
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = PNG_FORMAT_RGB;
  if (!png_image_write_to_file(&image, path.c_str(), /*convert_to_8bit=*/0, rgb.data(),
                               /*row_stride=*/0, /*colormap=*/nullptr)) {
    const std::string why = image.message;
    png_image_free(&image);
    return MakeError(ErrorCode::kIoError, path.string() + ": cannot write PNG: " + why);
  }
  return {};
}

Result<PngImage> ReadPng(const std::filesystem::path& path) {
  // Read the bytes ourselves: a missing file is an io_error, a bad one a parse_error.
  Result<std::string> bytes = internal::ReadFileBytes(path);
  if (!bytes.ok()) return bytes.error();
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, bytes->data(), bytes->size())) {
    const std::string why = image.message;
    png_image_free(&image);
    return MakeError(ErrorCode::kParseError, path.string() + ": not a PNG file: " + why);
  }
  image.format = PNG_FORMAT_RGB;
  PngImage png;
  png.width = static_cast<int>(image.width);
  png.height = static_cast<int>(image.height);
  png.rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, /*background=*/nullptr, png.rgb.data(), /*row_stride=*/0,
                             /*colormap=*/nullptr)) {
    const std::string why = image.message;
    png_image_free(&image);
    return MakeError(ErrorCode::kParseError, path.string() + ": broken PNG file: " + why);
  }
  return png;
}

}  // namespace far
