// Small string helpers shared by the client's formatting code.
#ifndef MAPD_CLIENT_TEXT_UTIL_H_
#define MAPD_CLIENT_TEXT_UTIL_H_

#include <cstdarg>
#include <cstdio>
#include <string>

namespace mapd::client {

// printf into a std::string, of any length.
inline std::string Printf(const char* format, ...) __attribute__((format(printf, 1, 2)));
inline std::string Printf(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  std::string out(n > 0 ? static_cast<size_t>(n) : 0, '\0');
  if (n > 0) std::vsnprintf(&out[0], out.size() + 1, format, args);
  va_end(args);
  return out;
}

// Escapes text for an XML (SVG) text node or attribute value.
inline std::string XmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace mapd::client

#endif  // MAPD_CLIENT_TEXT_UTIL_H_
