#include "upd/io/png_gray16.h"

#include <png.h>

#include <cstring>

namespace upd::io {

namespace {

// The bytes libpng reads, and the first error it reports.
struct Source {
  const unsigned char* bytes;
  std::size_t size, at;
  char error[256];
};

// libpng's handlers: an error is kept and ends the decode by libpng's longjmp (never through a
// C++ frame with a destructor: see decodeInto); warnings (an ancillary chunk's CRC, an sRGB
// profile libpng dislikes) are not errors of the depth image and are dropped.
extern "C" void keepError(png_structp png, png_const_charp message) {
  auto* s = static_cast<Source*>(png_get_error_ptr(png));
  std::strncpy(s->error, message ? message : "libpng error", sizeof s->error - 1);
  s->error[sizeof s->error - 1] = '\0';
  png_longjmp(png, 1);
}
extern "C" void dropWarning(png_structp, png_const_charp) {}

extern "C" void readBytes(png_structp png, png_bytep out, png_size_t n) {
  auto* s = static_cast<Source*>(png_get_io_ptr(png));
  if (n > s->size - s->at) png_error(png, "file cut short");
  std::memcpy(out, s->bytes + s->at, n);
  s->at += n;
}

int channelsOf(int color_type) {
  switch (color_type) {
    case PNG_COLOR_TYPE_GRAY: return 1;
    case PNG_COLOR_TYPE_GRAY_ALPHA: return 2;
    case PNG_COLOR_TYPE_RGB_ALPHA: return 4;
    default: return 3;  // RGB, and a palette of RGB entries
  }
}

// The decode between libpng's setjmp and its longjmp: only trivially destructible locals, and
// the image's buffers sized by the caller's resize callback before libpng writes into them.
// Returns false where libpng reported an error (in src.error).
template <class Resize>
bool decodeInto(png_structp png, png_infop info, Source& src, Gray16& out, Resize& resize) {
  using Status = Gray16::Status;
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_read_fn(png, &src, readBytes);
  png_read_info(png, info);
  out.width = png_get_image_width(png, info);
  out.height = png_get_image_height(png, info);
  out.bit_depth = png_get_bit_depth(png, info);
  out.channels = channelsOf(png_get_color_type(png, info));
  if (out.bit_depth != 16 || out.channels != 1) {
    out.status = Status::NotGray16;
    return true;
  }
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  png_set_swap(png);  // (PNG's samples are big-endian)
#endif
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  png_bytep* rows = resize(out);
  png_read_image(png, rows);
  png_read_end(png, nullptr);
  out.status = Status::Gray16;
  return true;
}

}  // namespace

Gray16 decodeGray16(const unsigned char* bytes, std::size_t n, std::uint32_t max_side,
                    std::uint64_t max_pixels) {
  Gray16 out;
  // The signature and the first chunk, IHDR, whose size is checked here, before libpng checks
  // its CRC and allocates for it.
  if (n < 24 || png_sig_cmp(bytes, 0, 8) != 0 || std::memcmp(bytes + 12, "IHDR", 4) != 0) {
    return out;  // (NotPng)
  }
  out.width = png_get_uint_32(bytes + 16);
  out.height = png_get_uint_32(bytes + 20);
  if (out.width == 0 || out.height == 0 || out.width > max_side || out.height > max_side ||
      std::uint64_t{out.width} * out.height > max_pixels) {
    out.status = Gray16::Status::TooLarge;
    return out;
  }
  Source src{bytes, n, 0, {}};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &src, keepError, dropWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    out.status = Gray16::Status::Damaged;
    out.error = "out of memory";
    return out;
  }
  // (The pixels and row pointers are allocated here, outside the frame libpng jumps out of.)
  std::vector<png_bytep> rows;
  auto resize = [&](Gray16& g) {
    g.pixels.assign(std::size_t{g.width} * g.height, 0);
    rows.resize(g.height);
    for (std::uint32_t r = 0; r < g.height; ++r) {
      rows[r] = reinterpret_cast<png_bytep>(g.pixels.data() + std::size_t{r} * g.width);
    }
    return rows.data();
  };
  if (!decodeInto(png, info, src, out, resize)) {
    out.status = Gray16::Status::Damaged;
    out.error = src.error;
    out.pixels.clear();
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return out;
}

std::string whyNotGray16(const Gray16& g, std::uint32_t max_side, std::uint64_t max_pixels) {
  switch (g.status) {
    case Gray16::Status::NotPng: return "not a PNG image";
    case Gray16::Status::TooLarge:
      return std::to_string(g.width) + " x " + std::to_string(g.height) +
             " pixels by its header: a depth image has 1 to " + std::to_string(max_side) +
             " a side and at most " + std::to_string(max_pixels) + " in all";
    case Gray16::Status::Damaged: return "damaged PNG (" + g.error + ")";
    case Gray16::Status::NotGray16:
      return std::to_string(g.bit_depth) + "-bit, " + std::to_string(g.channels) +
             " channel(s); a depth image is 16-bit single channel";
    case Gray16::Status::Gray16: break;
  }
  return "";
}

}  // namespace upd::io
