#include "client/png_writer.h"

#include <zlib.h>

#include <algorithm>
#include <vector>

namespace mapd::client {
namespace {

void AppendBigEndian32(uint32_t v, std::string* out) {
  out->push_back(static_cast<char>((v >> 24) & 0xff));
  out->push_back(static_cast<char>((v >> 16) & 0xff));
  out->push_back(static_cast<char>((v >> 8) & 0xff));
  out->push_back(static_cast<char>(v & 0xff));
}

// length, type, data, CRC over type + data.
void AppendChunk(const char type[4], std::string_view data, std::string* out) {
  AppendBigEndian32(static_cast<uint32_t>(data.size()), out);
  std::string typed(type, 4);
  typed.append(data.data(), data.size());
  out->append(typed);
  AppendBigEndian32(PngCrc32(typed), out);
}

}  // namespace

uint32_t PngCrc32(std::string_view bytes) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes uInt lengths: feed large inputs in pieces.
  while (!bytes.empty()) {
    const size_t n = std::min<size_t>(bytes.size(), 1u << 30);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(n));
    bytes.remove_prefix(n);
  }
  return static_cast<uint32_t>(crc);
}

StatusOr<std::string> EncodePng(const RgbImage& image) {
  if (image.width() < 1 || image.height() < 1) {
    return Status::InvalidArgument("a PNG needs at least 1x1 pixels, got " + std::to_string(image.width()) +
                                   "x" + std::to_string(image.height()));
  }
  std::string out(kPngSignature, 8);

  std::string ihdr;
  AppendBigEndian32(static_cast<uint32_t>(image.width()), &ihdr);
  AppendBigEndian32(static_cast<uint32_t>(image.height()), &ihdr);
  // Bit depth 8, colour type 2 (RGB), compression 0 (deflate), filter method 0, no interlace.
  ihdr += std::string("\x08\x02\x00\x00\x00", 5);
  AppendChunk("IHDR", ihdr, &out);

  // Each scanline: filter type 0 (None), then the row's RGB bytes.
  const size_t row_bytes = static_cast<size_t>(image.width()) * 3;
  std::vector<uint8_t> raw;
  raw.reserve((row_bytes + 1) * static_cast<size_t>(image.height()));
  for (int y = 0; y < image.height(); ++y) {
    raw.push_back(0);
    const uint8_t* row = image.bytes().data() + static_cast<size_t>(y) * row_bytes;
    raw.insert(raw.end(), row, row + row_bytes);
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::string packed(packed_size, '\0');
  const int rc = compress2(reinterpret_cast<Bytef*>(&packed[0]), &packed_size, raw.data(),
                           static_cast<uLong>(raw.size()), Z_BEST_COMPRESSION);
  if (rc != Z_OK) return Status::Internal("zlib compress2 failed with code " + std::to_string(rc));
  packed.resize(packed_size);
  AppendChunk("IDAT", packed, &out);
  AppendChunk("IEND", "", &out);
  return out;
}

std::string Base64(std::string_view bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const uint32_t v = (static_cast<uint8_t>(bytes[i]) << 16) | (static_cast<uint8_t>(bytes[i + 1]) << 8) |
                       static_cast<uint8_t>(bytes[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out.push_back(kAlphabet[(v >> s) & 63]);
  }
  const size_t rest = bytes.size() - i;
  if (rest > 0) {
    uint32_t v = static_cast<uint8_t>(bytes[i]) << 16;
    if (rest == 2) v |= static_cast<uint8_t>(bytes[i + 1]) << 8;
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(rest == 2 ? kAlphabet[(v >> 6) & 63] : '=');
    out.push_back('=');
  }
  return out;
}

}  // namespace mapd::client
