// Makes untrusted text safe for one line of a log, a table or a terminal.
//
// Ids are validated where they enter, but free text (reasons, error
// messages, names kept from older versions) reaches log lines, the audit
// table and `mapctl` output. A newline there forges a row; an ESC there
// drives the operator's terminal. EscapeControlChars writes every character
// that could do either as visible text:
//   \n \r \t                      for LF, CR, TAB
//   \xHH                          for the other C0 controls, DEL, and bytes
//                                 that are not valid UTF-8
//   \u0080 .. \u009f, \u202e ...  for C1 controls (CSI, U+009B, acts as ESC [)
//                                 and the bidirectional overrides and isolates
//                                 (U+202A-U+202E, U+2066-U+2069), which can
//                                 make a terminal show text in another order
// and, with `escape_backslash`, a backslash as \\ (so that an escaped
// newline and a typed "\n" differ: the logfmt writer asks for that).
// Everything else, valid UTF-8 included, passes unchanged.
#ifndef MAPD_COMMON_TEXT_ESCAPE_H_
#define MAPD_COMMON_TEXT_ESCAPE_H_

#include <cstdio>
#include <string>
#include <string_view>

namespace mapd {

namespace text_escape_internal {

// Length of the valid UTF-8 sequence starting at s[i] (2-4), or 0.
inline size_t Utf8Length(std::string_view s, size_t i) {
  const auto b = [&](size_t k) { return static_cast<unsigned char>(s[i + k]); };
  const auto cont = [&](size_t k) { return i + k < s.size() && (b(k) & 0xC0) == 0x80; };
  const unsigned char c = b(0);
  if (c >= 0xC2 && c <= 0xDF) return cont(1) ? 2 : 0;
  if (c >= 0xE0 && c <= 0xEF) {
    if (!cont(1) || !cont(2)) return 0;
    if (c == 0xE0 && b(1) < 0xA0) return 0;  // overlong
    if (c == 0xED && b(1) > 0x9F) return 0;  // surrogates
    return 3;
  }
  if (c >= 0xF0 && c <= 0xF4) {
    if (!cont(1) || !cont(2) || !cont(3)) return 0;
    if (c == 0xF0 && b(1) < 0x90) return 0;  // overlong
    if (c == 0xF4 && b(1) > 0x8F) return 0;  // above U+10FFFF
    return 4;
  }
  return 0;
}

inline void AppendHex(const char* prefix, unsigned value, int digits, std::string* out) {
  char text[12];
  std::snprintf(text, sizeof(text), "%s%0*x", prefix, digits, value);
  out->append(text);
}

}  // namespace text_escape_internal

inline std::string EscapeControlChars(std::string_view s, bool escape_backslash = false) {
  using text_escape_internal::AppendHex;
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x80) {
      const size_t n = text_escape_internal::Utf8Length(s, i);
      if (n == 0) {
        AppendHex("\\x", c, 2, &out);
        ++i;
        continue;
      }
      unsigned code = 0;
      if (n == 2) code = ((c & 0x1Fu) << 6) | (static_cast<unsigned char>(s[i + 1]) & 0x3Fu);
      if (n == 3) {
        code = ((c & 0x0Fu) << 12) | ((static_cast<unsigned char>(s[i + 1]) & 0x3Fu) << 6) |
               (static_cast<unsigned char>(s[i + 2]) & 0x3Fu);
      }
      const bool c1 = code >= 0x80 && code <= 0x9F;
      const bool bidi = (code >= 0x202A && code <= 0x202E) || (code >= 0x2066 && code <= 0x2069);
      if (c1 || bidi) {
        AppendHex("\\u", code, 4, &out);
      } else {
        out.append(s.substr(i, n));
      }
      i += n;
      continue;
    }
    switch (c) {
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\\':
        out += escape_backslash ? "\\\\" : "\\";
        break;
      default:
        if (c < 0x20 || c == 0x7F) {
          AppendHex("\\x", c, 2, &out);
        } else {
          out.push_back(static_cast<char>(c));
        }
    }
    ++i;
  }
  return out;
}

}  // namespace mapd

#endif  // MAPD_COMMON_TEXT_ESCAPE_H_
