#pragma once
// The step options shared by far-client collide, play and load and by far-snapshot (--method,
// --resolution, --distance, ...).
#include <string>

#include <CLI/CLI.hpp>

#include "far/base/result.h"
#include "far/client/client.h"
#include "far/model/step_request.h"

namespace far::cli {

struct StepFlags {
  std::string method = "auto", mechanism = "id-buffer", output, depth = "depth24";
  std::string timeout = "60s";
  int resolution = 1024, subobject_size = 1;
  double distance = 0;
  bool geometry = false;
  CLI::Option* distance_option = nullptr;

  /// Adds the options of the request to `command`.
  void Add(CLI::App* command);
  /// Adds --timeout, for the commands whose steps run in a daemon (not far-snapshot's).
  void AddTimeout(CLI::App* command);
  /// The request the options describe, or an error naming the bad option.
  Result<StepRequest> Request() const;
  /// The client options for these steps: `base` with --timeout.
  Result<client::ClientOptions> Options(const client::ClientOptions& base) const;
};

}  // namespace far::cli
