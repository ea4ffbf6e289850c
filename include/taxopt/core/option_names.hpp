#pragma once
/// @file How a caller names the library's options in the messages it gets back.

#include <map>
#include <string>

#include "taxopt/core/export.hpp"

namespace taxopt {

/// A message that tells the caller which option to set names it by its field
/// ("JobOptions::spindle_rpm", "ClReadOptions::skip_records"). A caller that shows its users
/// other names — a command line's flags, a dialog's labels — maps the fields to them here
/// (JobOptions::option_names, ClReadOptions::option_names) and the messages use those: the
/// taxopt CLI maps "JobOptions::spindle_rpm" to "--spindle-rpm". A field not in the map keeps
/// its own name.
using OptionNames = std::map<std::string, std::string>;

/// `field` as the caller names it: names[field], else `field` itself.
TAXOPT_API std::string option_name(const OptionNames& names, const std::string& field);

}  // namespace taxopt
