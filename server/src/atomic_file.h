#pragma once

#include <string>

#include "far/base/result.h"

namespace far::server {

/// Replaces `path` with `text` atomically: writes a temporary file beside it (a dot file, which
/// node_exporter's textfile collector, reading *.prom only, never reads), makes it readable by
/// all (a metrics collector runs as another user) and renames it over `path`, so that a reader sees
/// the old file or the new one, never part of one. Errors: kIoError naming the path and errno.
Result<void> WriteFileAtomically(const std::string& path, const std::string& text);

}  // namespace far::server
