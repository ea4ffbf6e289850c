#pragma once
/// @file Small text helpers shared by the readers.

#include <cctype>
#include <charconv>
#include <cstddef>
#include <cstdio>
#include <string>

namespace taxopt::detail {

/// `s` without leading and trailing white space.
inline std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

/// A number as printf's "%.*f" writes it, NUL-terminated: room for the longest double in %f
/// (309 digits), its sign and point, and the decimals taxopt writes.
struct FixedText {
  char text[401];
  std::size_t size;
};

/// `v` with `decimals` decimals exactly as printf's "%.*f" writes it in the C locale:
/// std::to_chars with a precision is specified so (C++17 [charconv]), at a fraction of
/// printf's cost; printf where it would not fit.
inline FixedText fixed_text(double v, int decimals) {
  FixedText f{};
  const std::to_chars_result r =
      std::to_chars(f.text, f.text + sizeof f.text - 1, v, std::chars_format::fixed, decimals);
  if (r.ec == std::errc()) {
    *r.ptr = '\0';
  } else {
    std::snprintf(f.text, sizeof f.text, "%.*f", decimals, v);
  }
  f.size = std::char_traits<char>::length(f.text);
  return f;
}

}  // namespace taxopt::detail
