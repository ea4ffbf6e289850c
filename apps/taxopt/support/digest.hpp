#pragma once
/// @file SHA-256 of a byte string (FIPS 180-4), for the report's record of the machine file:
/// the same digest `sha256sum` prints.

#include <string>

namespace taxopt {

/// Lower-case hexadecimal SHA-256 of `bytes`.
std::string sha256_hex(const std::string& bytes);

}  // namespace taxopt
