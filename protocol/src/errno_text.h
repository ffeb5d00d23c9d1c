#pragma once

#include <cstring>
#include <string>

namespace far::protocol {

/// The system's text for an errno value, as a std::string (so it concatenates after a literal).
inline std::string ErrnoText(int error) { return std::strerror(error); }

}  // namespace far::protocol
