#pragma once

// Floods that a client can aim at the daemon's log (issue 41): one session sending step
// requests without waiting for their answers (each one past the session's queue or request
// rate is refused "busy"), and one user opening sessions in a loop (those over the open rate
// are refused). Each reports what it sent; LogGrowth says what the daemon's log gained.

#include <cstdint>
#include <map>
#include <string>

#include "study_daemon.h"

namespace far::study {

struct LogFloodReport {
  int64_t sent = 0;     ///< step requests sent, or opens tried
  int64_t refused = 0;  ///< opens refused (the open flood only)
  double seconds = 0;
  std::string error;  ///< why the flood could not run ("" when it ran)
};

/// Opens one session (a single object) and sends step requests back to back, without
/// waiting for their answers, for `seconds`.
LogFloodReport StepFlood(const StudyDaemon& daemon, double seconds);

/// Opens sessions back to back for `seconds`, closing each one that opens at once.
LogFloodReport OpenFlood(const StudyDaemon& daemon, double seconds);

/// What the daemon's log gained after byte `from`: its bytes, lines, and lines per event.
struct LogGrowth {
  int64_t bytes = 0, lines = 0;
  std::map<std::string, int64_t> lines_by_event;
  /// "step_error 1234, open_refused 56" (most first).
  std::string Events() const;
};
LogGrowth LogGrowthSince(const StudyDaemon& daemon, int64_t from);

}  // namespace far::study
