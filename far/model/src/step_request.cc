#include "far/model/step_request.h"

#include <array>
#include <utility>

namespace far {
namespace {

template <typename Enum, size_t N>
using NameTable = std::array<std::pair<Enum, std::string_view>, N>;

constexpr NameTable<Method, 6> kMethodNames{{{Method::kAabb, "aabb"},
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

}  // namespace

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
