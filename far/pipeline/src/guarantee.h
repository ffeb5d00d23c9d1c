#pragma once

// Why a step's answer holds every contact, or why it may not: the words of a reply's
// certificate (far::Certificate). The numbers come from the culling levels themselves.

#include <string>

#include "far/model/step_request.h"

namespace far::internal {

/// The basis of the certificate of a step run with `request` (a concrete method, not auto).
std::string GuaranteeBasis(const StepRequest& request);

}  // namespace far::internal
