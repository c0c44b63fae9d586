// Small string helpers shared by the client's formatting code.
#ifndef MAPD_CLIENT_TEXT_UTIL_H_
#define MAPD_CLIENT_TEXT_UTIL_H_

#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <string>
#include <string_view>

#include "common/text_escape.h"

namespace mapd::client {

// Text from the server (or a file) for one line of a terminal: control
// characters, C1 controls and bidi overrides shown escaped, never sent raw
// (common/text_escape.h). Every free-text field mapctl prints goes through
// it; ids are validated by mapd but older databases may hold anything.
inline std::string Visible(std::string_view s) { return EscapeControlChars(s); }

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

// A server time (ns since the Unix epoch) as UTC ISO 8601; "-" for 0 (unset).
inline std::string IsoTime(int64_t ns) {
  if (ns <= 0) return "-";
  const auto secs = static_cast<std::time_t>(ns / 1000000000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char out[32];
  std::strftime(out, sizeof(out), "%Y-%m-%dT%H:%M:%SZ", &tm);
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
