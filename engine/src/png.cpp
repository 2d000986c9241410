// PNG reading and writing (see png.h): every decoder goes through begin_read and
// finish_read below, so the checks (signature, size, payload) and the messages are
// written once; callers differ only in the pixel format they ask libpng for.
#include "hsi/png.h"

#include <png.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>

#include "hsi/domain.h"

namespace hsi {

namespace {

// Who reads, for the wording of the messages: a plain image (textures of the
// renderer, frames, screenshots), import-png's sprite, or glTF export's texture check.
enum class Use { kImage, kSprite, kTexture };

// Frees libpng's state however we leave (png_image_free is safe to call twice).
struct PngImageGuard {
  png_image* image;
  ~PngImageGuard() { png_image_free(image); }
};

std::string subject(const std::string& name, Use use) { return name + ": " + (use == Use::kTexture ? "the texture is " : ""); }

std::string size_error(const std::string& name, Use use, png_uint_32 w, png_uint_32 h) {
  const std::string max = std::to_string(kPngMaxSide);
  switch (use) {
    case Use::kSprite:
      return name + ": image too large (" + std::to_string(w) + "x" + std::to_string(h) + " px; at most " + max +
             " px on a side)";
    case Use::kTexture:
      return name + ": the texture's size " + std::to_string(w) + "x" + std::to_string(h) + " px is outside 1.." + max +
             " px on a side";
    case Use::kImage: break;
  }
  return name + ": image size " + std::to_string(w) + " x " + std::to_string(h) + " is outside 1.." + max;
}

// Checks the signature, reads the header, the size and the payload's plausibility.
void begin_read(png_image& image, std::span<const unsigned char> data, const std::string& name, Use use) {
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (data.size() < 8 || !std::equal(std::begin(kSignature), std::end(kSignature), data.begin()))
    throw InputError(subject(name, use) + "not a PNG file (" +
                     (data.empty() ? std::string("the file is empty") : std::string("bad signature")) + ")");
  image = png_image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, data.data(), data.size()))
    throw InputError(subject(name, use) + "corrupt or truncated PNG data (libpng: " + image.message + ")");
  const auto max = static_cast<png_uint_32>(kPngMaxSide);
  if (image.width == 0 || image.height == 0 || image.width > max || image.height > max)
    throw InputError(size_error(name, use, image.width, image.height));
  check_png_payload(data, use == Use::kTexture ? name + " (texture)" : name);
}

// Decodes the pixels in image.format into `out` (PNG_IMAGE_SIZE(image) bytes).
void finish_read(png_image& image, void* out, const std::string& name, Use use) {
  if (!png_image_finish_read(&image, nullptr, out, 0, nullptr))
    throw InputError(subject(name, use) + "corrupt or truncated PNG data (libpng: " + image.message + ")");
}

RgbaImage decode_rgba(std::span<const unsigned char> data, const std::string& name, Use use) {
  png_image image{};
  PngImageGuard guard{&image};
  begin_read(image, data, name, use);
  image.format = PNG_FORMAT_RGBA;
  RgbaImage out(static_cast<int>(image.width), static_cast<int>(image.height));
  finish_read(image, out.pixels.data(), name, use);
  return out;
}

std::string describe_format(png_uint_32 format) {
  if (format & PNG_FORMAT_FLAG_COLORMAP) return "palette without a tRNS chunk";
  return (format & PNG_FORMAT_FLAG_COLOR) ? "RGB" : "greyscale";
}

}  // namespace

RgbaImage::RgbaImage(int w, int h, std::array<uint8_t, 4> fill) : width(w), height(h) {
  if (w < 0 || h < 0) throw InputError("image: negative size " + std::to_string(w) + " x " + std::to_string(h));
  pixels.resize(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
  for (size_t i = 0; i < pixels.size(); i += 4) std::memcpy(&pixels[i], fill.data(), 4);
}

std::vector<unsigned char> read_png_bytes(const std::filesystem::path& path, const std::string& name) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(name + ": no such file");
  if (std::filesystem::is_directory(path, ec)) throw InputError(name + ": is a directory, not a PNG file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(name + ": cannot open the file for reading");
  std::vector<unsigned char> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(name + ": read error");
  return data;
}

RgbaImage decode_png(std::span<const unsigned char> png_bytes, const std::string& name) {
  return decode_rgba(png_bytes, name, Use::kImage);
}

RgbaImage read_png(const std::filesystem::path& path) {
  const std::string name = path.string();
  return decode_rgba(read_png_bytes(path, name), name, Use::kImage);
}

std::array<int, 2> check_png_texture(std::span<const unsigned char> png_bytes, const std::string& name) {
  const RgbaImage image = decode_rgba(png_bytes, name, Use::kTexture);
  return {image.width, image.height};
}

PngAlpha decode_png_alpha(std::span<const unsigned char> data, const std::string& name) {
  png_image image{};
  PngImageGuard guard{&image};
  begin_read(image, data, name, Use::kSprite);
  if (!(image.format & PNG_FORMAT_FLAG_ALPHA))
    throw InputError(name + ": the image has no alpha channel (" + describe_format(image.format) +
                     "); import-png traces the alpha channel, so it needs RGBA, grey+alpha, or a palette or "
                     "colour key with transparency (tRNS)");
  PngAlpha out;
  out.width = static_cast<int>(image.width);
  out.height = static_cast<int>(image.height);
  const size_t n = static_cast<size_t>(image.width) * image.height;
  const bool sixteen = (image.format & PNG_FORMAT_FLAG_LINEAR) != 0;
  // 8-bit sources: grey+alpha, 2 bytes a pixel, read straight into one uint16_t a
  // pixel and then reduced in place to the alpha byte. 16-bit sources: linear
  // grey+alpha (alpha is not altered by libpng's premultiplication of grey).
  image.format = sixteen ? PNG_FORMAT_LINEAR_Y_ALPHA : PNG_FORMAT_GA;
  out.max_value = sixteen ? 65535.0 : 255.0;
  out.alpha.resize(sixteen ? 2 * n : n);
  if (PNG_IMAGE_SIZE(image) != out.alpha.size() * sizeof(uint16_t))
    throw InputError(name + ": unexpected decoded image size");  // cannot happen; guards the buffer
  finish_read(image, out.alpha.data(), name, Use::kSprite);
  if (image.warning_or_error & PNG_IMAGE_WARNING) out.warnings.push_back(std::string("libpng: ") + image.message);
  if (sixteen) {
    for (size_t i = 0; i < n; ++i) out.alpha[i] = out.alpha[2 * i + 1];
    out.alpha.resize(n);
    out.alpha.shrink_to_fit();
  } else {
    const unsigned char* bytes = reinterpret_cast<const unsigned char*>(out.alpha.data());
    for (size_t i = 0; i < n; ++i) out.alpha[i] = bytes[2 * i + 1];  // reads bytes of slot i only
  }
  return out;
}

void check_png_payload(std::span<const unsigned char> data, const std::string& name) {
  const auto be32 = [&](size_t at) {
    return (uint32_t{data[at]} << 24) | (uint32_t{data[at + 1]} << 16) | (uint32_t{data[at + 2]} << 8) | uint32_t{data[at + 3]};
  };
  // IHDR comes first: 8-byte signature, then length, "IHDR", width, height, depth, colour type.
  if (data.size() < 33 || std::memcmp(&data[12], "IHDR", 4) != 0) return;  // libpng reports these itself
  const uint64_t width = be32(16), height = be32(20);
  const unsigned depth = data[24], colour = data[25];
  const unsigned channels = colour == 0 ? 1 : colour == 2 ? 3 : colour == 3 ? 1 : colour == 4 ? 2 : colour == 6 ? 4 : 0;
  if (channels == 0 || depth == 0 || depth > 16) return;  // invalid header: libpng's message names it
  // Sum the IDAT chunks' lengths (as far as the file goes).
  uint64_t compressed = 0;
  for (size_t at = 8; at + 8 <= data.size();) {
    const uint64_t length = be32(at);
    if (std::memcmp(&data[at + 4], "IDAT", 4) == 0) compressed += std::min<uint64_t>(length, data.size() - (at + 8));
    at += static_cast<size_t>(std::min<uint64_t>(12 + length, data.size()));
  }
  // The filtered rows the zlib stream must expand to (non-interlaced; interlacing adds more).
  const uint64_t raw = height * (1 + (width * channels * depth + 7) / 8);
  constexpr uint64_t kDeflateMaxRatio = 1032;
  if (raw > kDeflateMaxRatio * compressed + 1024)
    throw InputError(name + ": truncated or corrupt PNG: its header claims " + std::to_string(width) + "x" +
                     std::to_string(height) + " px (" + std::to_string(raw) + " bytes of rows) but it holds only " +
                     std::to_string(compressed) + " bytes of image data, which cannot expand to that");
}

void write_png(const std::filesystem::path& path, const RgbaImage& image) {
  if (image.empty() || image.pixels.size() != static_cast<size_t>(image.width) * static_cast<size_t>(image.height) * 4)
    throw InputError(path.string() + ": cannot write an empty or inconsistent image");
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  img.width = static_cast<png_uint_32>(image.width);
  img.height = static_cast<png_uint_32>(image.height);
  img.format = PNG_FORMAT_RGBA;
  png_alloc_size_t size = 0;
  if (!png_image_write_get_memory_size(img, size, 0, image.pixels.data(), 0, nullptr))
    throw InputError(path.string() + ": PNG encoding failed (" + img.message + ")");
  std::string bytes(size, '\0');
  if (!png_image_write_to_memory(&img, bytes.data(), &size, 0, image.pixels.data(), 0, nullptr))
    throw InputError(path.string() + ": PNG encoding failed (" + img.message + ")");
  bytes.resize(size);
  write_file_atomic(path, bytes);
}

}  // namespace hsi
