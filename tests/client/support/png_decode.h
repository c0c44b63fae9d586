// A strict decoder for the PNG files mapctl writes (8-bit RGB, unfiltered
// scanlines, no interlace), for tests: it checks the signature, the order of
// IHDR / IDAT / IEND and every chunk's CRC with its own bitwise CRC-32 (not
// zlib's, so the encoder is checked against an independent implementation),
// then inflates the pixels. Header-only.
#ifndef MAPD_TESTS_CLIENT_SUPPORT_PNG_DECODE_H_
#define MAPD_TESTS_CLIENT_SUPPORT_PNG_DECODE_H_

#include <zlib.h>

#include <cstdint>
#include <string>
#include <vector>

namespace mapd::testing {

// CRC-32 (polynomial 0xEDB88320, reflected), one bit at a time.
inline uint32_t BitwiseCrc32(const std::string& bytes) {
  uint32_t crc = 0xffffffffu;
  for (unsigned char byte : bytes) {
    crc ^= byte;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xffffffffu;
}

struct DecodedPng {
  int width = 0, height = 0;
  std::vector<std::string> chunk_types;  // in file order
  std::vector<uint8_t> rgb;              // row-major, 3 bytes per pixel
  uint8_t r(int x, int y) const { return rgb[(static_cast<size_t>(y) * width + x) * 3]; }
  uint8_t g(int x, int y) const { return rgb[(static_cast<size_t>(y) * width + x) * 3 + 1]; }
  uint8_t b(int x, int y) const { return rgb[(static_cast<size_t>(y) * width + x) * 3 + 2]; }
};

// False with `*error` set on anything unexpected.
inline bool DecodePng(const std::string& file, DecodedPng* out, std::string* error) {
  auto u32 = [&](size_t at) {
    return (uint32_t{static_cast<uint8_t>(file[at])} << 24) | (uint32_t{static_cast<uint8_t>(file[at + 1])} << 16) |
           (uint32_t{static_cast<uint8_t>(file[at + 2])} << 8) | uint32_t{static_cast<uint8_t>(file[at + 3])};
  };
  if (file.size() < 8 || file.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) != 0) {
    *error = "bad signature";
    return false;
  }
  std::string idat;
  size_t at = 8;
  bool have_end = false;
  while (at < file.size()) {
    if (have_end) {
      *error = "bytes after IEND";
      return false;
    }
    if (at + 12 > file.size()) {
      *error = "truncated chunk header";
      return false;
    }
    const uint32_t length = u32(at);
    if (at + 12 + length > file.size()) {
      *error = "truncated chunk";
      return false;
    }
    const std::string typed = file.substr(at + 4, 4 + length);
    const std::string type = typed.substr(0, 4);
    if (BitwiseCrc32(typed) != u32(at + 8 + length)) {
      *error = "bad CRC in " + type;
      return false;
    }
    if (out->chunk_types.empty() && type != "IHDR") {
      *error = "first chunk is " + type;
      return false;
    }
    out->chunk_types.push_back(type);
    const std::string data = typed.substr(4);
    if (type == "IHDR") {
      if (length != 13) {
        *error = "IHDR length " + std::to_string(length);
        return false;
      }
      out->width = static_cast<int>(u32(at + 8));
      out->height = static_cast<int>(u32(at + 12));
      if (data.substr(8, 5) != std::string("\x08\x02\x00\x00\x00", 5)) {
        *error = "not 8-bit RGB, deflate, no interlace";
        return false;
      }
    } else if (type == "IDAT") {
      idat += data;
    } else if (type == "IEND") {
      have_end = true;
    }
    at += 12 + length;
  }
  if (!have_end) {
    *error = "no IEND";
    return false;
  }
  const size_t row_bytes = static_cast<size_t>(out->width) * 3;
  std::vector<uint8_t> raw((row_bytes + 1) * static_cast<size_t>(out->height) + 1);
  uLongf raw_size = static_cast<uLongf>(raw.size());
  if (uncompress(raw.data(), &raw_size, reinterpret_cast<const Bytef*>(idat.data()),
                 static_cast<uLong>(idat.size())) != Z_OK ||
      raw_size != raw.size() - 1) {
    *error = "IDAT does not inflate to the image size";
    return false;
  }
  out->rgb.clear();
  for (int y = 0; y < out->height; ++y) {
    const uint8_t* row = raw.data() + static_cast<size_t>(y) * (row_bytes + 1);
    if (row[0] != 0) {
      *error = "scanline filter " + std::to_string(row[0]);
      return false;
    }
    out->rgb.insert(out->rgb.end(), row + 1, row + 1 + row_bytes);
  }
  return true;
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_CLIENT_SUPPORT_PNG_DECODE_H_
