// Facts about the SVG files cairo writes, for tests: cairo draws every stroke
// and fill as a <path> with its colour as "rgb(R%,G%,B%)" (1.16: in a style
// attribute; later versions in a stroke/fill attribute), so shapes of one
// colour are counted by the "rgb(R%" prefix of that colour. Header-only.
#ifndef MAPD_TESTS_CLIENT_SUPPORT_SVG_FACTS_H_
#define MAPD_TESTS_CLIENT_SUPPORT_SVG_FACTS_H_

#include <cstdio>
#include <string>

namespace mapd::testing {

inline size_t CountSubstr(const std::string& text, const std::string& needle) {
  size_t n = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

// "rgb(12.156863%" for "#1f77b4": cairo prints each channel in percent with
// six decimals, trailing zeros dropped.
inline std::string CairoRedPrefix(const char* hex) {
  unsigned r = 0, g = 0, b = 0;
  std::sscanf(hex, "#%02x%02x%02x", &r, &g, &b);
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%f", r / 255.0 * 100);
  std::string s = buf;
  while (!s.empty() && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return "rgb(" + s + "%";
}

// The number of shapes painted in `hex` (its red channel must be unique in the drawing).
inline size_t CountShapesOfColour(const std::string& svg, const char* hex) {
  return CountSubstr(svg, CairoRedPrefix(hex));
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_CLIENT_SUPPORT_SVG_FACTS_H_
