#include "step_flags.h"

#include <cmath>

#include "cli_common.h"

namespace far::cli {

void StepFlags::AddTimeout(CLI::App* command) {
  command
      ->add_option("--timeout", timeout,
                   "wait this long for each step's reply while the daemon works on it (500ms, "
                   "60s, 2min: a unit is required); a daemon that stops ends the wait at once")
      ->capture_default_str();
}

void StepFlags::Add(CLI::App* command) {
  command
      ->add_option(
          "--method", method,
          "auto (the fastest reliable method for the daemon's renderer and the scene), "
          "bvh, aabb, gpu (compute shaders), far, far-exact-offset, cullide (not reliable), fcl or "
          "exact")
      ->capture_default_str();
  command->add_option("--mechanism", mechanism, "GPU methods: id-buffer or occlusion-query")
      ->capture_default_str();
  command
      ->add_option("--resolution", resolution,
                   "viewport size (8..8192; the daemon refuses more than its max_resolution, "
                   "default 4096)")
      ->capture_default_str();
  command->add_option("--depth-format", depth, "depth16, depth24 or depth32f")
      ->capture_default_str();
  command->add_option("--subobject-size", subobject_size, "triangles per sub-object")
      ->capture_default_str();
  distance_option = command->add_option(
      "--distance", distance, "distance D >= 0: report every triangle pair closer than D");
  command->add_option(
      "--output", output,
      "deepest output: object-pcs (objects only), pairs (object pairs), pcs (object and "
      "primitive PCS), contacts, "
      "distance (default: contacts, or distance when --distance is given)");
  command->add_flag("--geometry", geometry,
                    "also the contact geometry: where each contact's triangles meet and their "
                    "normals, each distance pair's closest points, each object pair's "
                    "penetration depth (needs output contacts or distance)");
}

Result<StepRequest> StepFlags::Request() const {
  far::StepRequest request;
  auto m = far::ParseMethod(method);
  if (!m)
    return far::MakeError(far::ErrorCode::kInvalidArgument, "--method: unknown '" + method + "'");
  auto k = far::ParseMechanism(mechanism);
  if (!k)
    return far::MakeError(far::ErrorCode::kInvalidArgument,
                          "--mechanism: unknown '" + mechanism + "'");
  auto d = far::ParseDepthFormat(depth);
  if (!d)
    return far::MakeError(far::ErrorCode::kInvalidArgument,
                          "--depth-format: unknown '" + depth + "'");
  request.method = *m;
  request.mechanism = *k;
  request.depth_format = *d;
  request.resolution = resolution;
  request.subobject_size = subobject_size;
  const bool has_distance = distance_option->count() > 0;
  if (has_distance) {
    if (!std::isfinite(distance) || distance < 0) {
      return far::MakeError(
          far::ErrorCode::kInvalidArgument,
          "--distance: " + std::to_string(distance) + " is not a finite number >= 0");
    }
    request.distance = distance;
  }
  std::string out = output.empty() ? (has_distance ? "distance" : "contacts") : output;
  auto o = far::ParseOutput(out);
  if (!o)
    return far::MakeError(far::ErrorCode::kInvalidArgument, "--output: unknown '" + out + "'");
  request.output = *o;
  request.geometry = geometry;
  return request;
}

Result<client::ClientOptions> StepFlags::Options(const client::ClientOptions& base) const {
  auto wait = ParseDuration("--timeout", timeout);
  if (!wait) return wait.error();
  client::ClientOptions options = base;
  options.timeout = *wait;
  return options;
}

}  // namespace far::cli
