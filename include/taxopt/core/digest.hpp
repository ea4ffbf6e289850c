#pragma once
/// @file SHA-256 of a byte string (FIPS 180-4), for the report's record of the machine file:
/// the same digest `sha256sum` prints.

#include <string>

#include "taxopt/core/export.hpp"

namespace taxopt {

/// Lower-case hexadecimal SHA-256 of `bytes`.
TAXOPT_API std::string sha256_hex(const std::string& bytes);

}  // namespace taxopt
