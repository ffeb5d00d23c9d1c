#pragma once

// What collide and play show while the daemon works on a long step: the step's state and stage
// on one line of stderr, rewritten in place. Only when stdout is a terminal: piped output stays
// exactly the results.

#include <string>

#include "far/client/client.h"

namespace far::cli {

/// A progress callback for step `label` ("step 3"), or an empty one when stdout is not a
/// terminal. Call EndProgress after the step to clear the line.
client::ProgressCallback ProgressLine(const std::string& label);
void EndProgress();

}  // namespace far::cli
