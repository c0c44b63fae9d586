// A minimal PNG encoder (8-bit RGB, no interlace) on zlib: signature, IHDR,
// one IDAT with every scanline unfiltered, IEND; each chunk with its CRC-32
// (PNG specification, 2nd edition, sections 5 and 11).
#ifndef MAPD_CLIENT_PNG_WRITER_H_
#define MAPD_CLIENT_PNG_WRITER_H_

#include <cstdint>
#include <string>
#include <string_view>

#include "client/rgb_image.h"
#include "common/status.h"

namespace mapd::client {

// The 8-byte PNG file signature.
inline constexpr char kPngSignature[] = "\x89PNG\r\n\x1a\n";

// CRC-32 as PNG computes it (ISO 3309 / zlib's crc32).
uint32_t PngCrc32(std::string_view bytes);

// The PNG file. InvalidArgument for an empty image (PNG needs width, height >= 1),
// Internal if zlib fails.
StatusOr<std::string> EncodePng(const RgbImage& image);

// Standard base64 (RFC 4648, with padding), for data: URIs.
std::string Base64(std::string_view bytes);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_PNG_WRITER_H_
