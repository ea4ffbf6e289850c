#pragma once
/// @file format_cl with a job's stop, internal to the library.

#include <string>
#include <vector>

#include "taxopt/core/stop.hpp"
#include "taxopt/io/cl_file.hpp"

namespace taxopt::cl {

/// format_cl looking at `stop`, where given, every few thousand records.
std::string format_cl(const Toolpath& original, const std::vector<Operationd>& operations,
                      const StopSource* stop);

}  // namespace taxopt::cl
