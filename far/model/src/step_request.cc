#include "far/model/step_request.h"

#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "far/base/limits.h"

namespace far {
namespace {

template <typename Enum, size_t N>
using NameTable = std::array<std::pair<Enum, std::string_view>, N>;

constexpr NameTable<Method, 9> kMethodNames{{{Method::kAuto, "auto"},
                                             {Method::kAabb, "aabb"},
                                             {Method::kBvh, "bvh"},
                                             {Method::kGpu, "gpu"},
                                             {Method::kCullide, "cullide"},
                                             {Method::kFar, "far"},
                                             {Method::kFarExactOffset, "far-exact-offset"},
                                             {Method::kFcl, "fcl"},
                                             {Method::kExact, "exact"}}};
constexpr NameTable<QueryMechanism, 2> kMechanismNames{
    {{QueryMechanism::kOcclusionQuery, "occlusion-query"},
     {QueryMechanism::kIdBuffer, "id-buffer"}}};
constexpr NameTable<Output, 5> kOutputNames{{{Output::kObjectPcs, "object-pcs"},
                                             {Output::kObjectPairs, "pairs"},
                                             {Output::kPrimitivePcs, "pcs"},
                                             {Output::kContacts, "contacts"},
                                             {Output::kDistancePairs, "distance"}}};
constexpr NameTable<DepthFormat, 3> kDepthNames{{{DepthFormat::kDepth16, "depth16"},
                                                 {DepthFormat::kDepth24, "depth24"},
                                                 {DepthFormat::kDepth32F, "depth32f"}}};

template <typename Enum, size_t N>
std::string_view NameOf(const NameTable<Enum, N>& table, Enum value) {
  for (const auto& [e, name] : table) {
    if (e == value) return name;
  }
  return "unknown";
}

template <typename Enum, size_t N>
std::optional<Enum> ValueOf(const NameTable<Enum, N>& table, std::string_view name) {
  for (const auto& [e, n] : table) {
    if (n == name) return e;
  }
  return std::nullopt;
}

Error InvalidField(const std::string& field, const std::string& what) {
  return MakeError(ErrorCode::kInvalidArgument, field + ": " + what);
}

std::string Range(int low, int high) {
  return "[" + std::to_string(low) + ", " + std::to_string(high) + "]";
}

template <typename Enum, size_t N>
std::string NamesOf(const NameTable<Enum, N>& table) {
  std::string names;
  for (const auto& [e, name] : table) names += (names.empty() ? "" : ", ") + std::string(name);
  return names;
}

// fcl's collide has no distance query; every other method answers one.
bool AnswersDistance(Method method) { return method != Method::kFcl; }

// "auto, aabb, bvh, ... or exact": the methods that answer distance queries, as the table has
// them.
std::string DistanceMethodNames() {
  std::vector<std::string_view> names;
  for (const auto& [method, name] : kMethodNames) {
    if (AnswersDistance(method)) names.push_back(name);
  }
  std::string text;
  for (size_t i = 0; i < names.size(); ++i) {
    text += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + std::string(names[i]);
  }
  return text;
}

}  // namespace

std::string MethodNames() { return NamesOf(kMethodNames); }
std::string MechanismNames() { return NamesOf(kMechanismNames); }
std::string OutputNames() { return NamesOf(kOutputNames); }
std::string DepthFormatNames() { return NamesOf(kDepthNames); }

bool IsReliable(Method method) { return method != Method::kCullide && method != Method::kFcl; }

bool IsGpuMethod(Method method) {
  return method == Method::kFar || method == Method::kFarExactOffset || method == Method::kCullide;
}

bool NeedsGl(Method method) { return IsGpuMethod(method) || method == Method::kGpu; }

Result<void> CheckStepRequest(const StepRequest& request) {
  if (request.resolution < kMinResolution || request.resolution > kMaxResolution) {
    return InvalidField("resolution", std::to_string(request.resolution) + " is outside " +
                                          Range(kMinResolution, kMaxResolution));
  }
  if (request.subobject_size < 1 || request.subobject_size > kMaxSubobjectSize) {
    return InvalidField("subobject_size", std::to_string(request.subobject_size) + " is outside " +
                                              Range(1, kMaxSubobjectSize));
  }
  if (request.distance && !(std::isfinite(*request.distance) && *request.distance >= 0 &&
                            *request.distance <= kMaxDistance)) {
    return InvalidField("distance", FormatDouble(*request.distance) +
                                        " is not a finite number in [0, " +
                                        FormatDouble(kMaxDistance) + "]");
  }
  if (request.output == Output::kDistancePairs && !request.distance) {
    return InvalidField("output", "'distance' needs a distance D");
  }
  if (!AnswersDistance(request.method) && request.distance) {
    return InvalidField("method", "'" + std::string(ToString(request.method)) +
                                      "' answers contacts only; distance queries need " +
                                      DistanceMethodNames());
  }
  if (request.geometry && request.output != Output::kContacts &&
      request.output != Output::kDistancePairs) {
    return InvalidField("geometry", "needs output 'contacts' or 'distance', not '" +
                                        std::string(ToString(request.output)) + "'");
  }
  return {};
}

std::string_view ToString(Method method) { return NameOf(kMethodNames, method); }
std::string_view ToString(QueryMechanism mechanism) { return NameOf(kMechanismNames, mechanism); }
std::string_view ToString(Output output) { return NameOf(kOutputNames, output); }
std::string_view ToString(DepthFormat format) { return NameOf(kDepthNames, format); }
std::optional<Method> ParseMethod(std::string_view name) { return ValueOf(kMethodNames, name); }
std::optional<QueryMechanism> ParseMechanism(std::string_view name) {
  return ValueOf(kMechanismNames, name);
}
std::optional<Output> ParseOutput(std::string_view name) { return ValueOf(kOutputNames, name); }
std::optional<DepthFormat> ParseDepthFormat(std::string_view name) {
  return ValueOf(kDepthNames, name);
}

}  // namespace far
