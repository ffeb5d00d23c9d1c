#include "request.h"

#include "errors.h"

namespace far::python {

StepRequest ToStepRequest(const std::string& method, const std::string& mechanism, int resolution,
                          const std::string& depth_format, int subobject_size,
                          std::optional<double> distance, std::optional<std::string> output,
                          bool geometry) {
  StepRequest request;
  auto m = ParseMethod(method);
  if (!m) ThrowArgument("method", "unknown '" + method + "'; the methods are: " + MethodNames());
  auto k = ParseMechanism(mechanism);
  if (!k) {
    ThrowArgument("mechanism",
                  "unknown '" + mechanism + "'; the mechanisms are: " + MechanismNames());
  }
  auto d = ParseDepthFormat(depth_format);
  if (!d) {
    ThrowArgument("depth_format",
                  "unknown '" + depth_format + "'; the formats are: " + DepthFormatNames());
  }
  const std::string out = output.value_or(distance ? "distance" : "contacts");
  auto o = ParseOutput(out);
  if (!o) ThrowArgument("output", "unknown '" + out + "'; the outputs are: " + OutputNames());
  request.method = *m;
  request.mechanism = *k;
  request.depth_format = *d;
  request.resolution = resolution;
  request.subobject_size = subobject_size;
  request.distance = distance;
  request.output = *o;
  request.geometry = geometry;
  Check(CheckStepRequest(request));
  return request;
}

}  // namespace far::python
