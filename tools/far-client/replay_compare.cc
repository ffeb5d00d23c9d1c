#include "replay_compare.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace far::cli {
namespace {

// Distances are computed by the same exact stage on every daemon; this only absorbs a
// different compiler's last-bit rounding.
constexpr double kDistanceTolerance = 1e-9;

std::string Describe(const ContactPair& p) {
  return "(object " + std::to_string(p.object_a) + " triangle " + std::to_string(p.triangle_a) +
         ", object " + std::to_string(p.object_b) + " triangle " + std::to_string(p.triangle_b) +
         ")";
}
std::string Describe(const ObjectPair& p) {
  return "(object " + std::to_string(p.object_a) + ", object " + std::to_string(p.object_b) + ")";
}
std::string Describe(uint32_t object) { return "object " + std::to_string(object); }
std::string Describe(const std::pair<uint32_t, uint32_t>& primitive) {
  return "object " + std::to_string(primitive.first) + " triangle " +
         std::to_string(primitive.second);
}

// The first element of two sorted ranges that only one holds, in words; "" when equal.
template <typename T>
std::string FirstDifference(const std::string& what, std::vector<T> recorded,
                            std::vector<T> replayed) {
  std::sort(recorded.begin(), recorded.end());
  std::sort(replayed.begin(), replayed.end());
  auto r = recorded.begin();
  auto p = replayed.begin();
  while (r != recorded.end() || p != replayed.end()) {
    if (p == replayed.end() || (r != recorded.end() && *r < *p)) {
      return what + " " + Describe(*r) + " recorded, not replayed (" +
             std::to_string(recorded.size()) + " recorded, " + std::to_string(replayed.size()) +
             " replayed)";
    }
    if (r == recorded.end() || *p < *r) {
      return what + " " + Describe(*p) + " replayed, not recorded (" +
             std::to_string(recorded.size()) + " recorded, " + std::to_string(replayed.size()) +
             " replayed)";
    }
    ++r;
    ++p;
  }
  return "";
}

std::vector<std::pair<uint32_t, uint32_t>> Primitives(const StepResult& result) {
  std::vector<std::pair<uint32_t, uint32_t>> all;
  for (const auto& [object, triangles] : result.pcs_primitives) {
    for (uint32_t t : triangles) all.emplace_back(object, t);
  }
  return all;
}

std::vector<ContactPair> DistancePairsOf(const StepResult& result) {
  std::vector<ContactPair> pairs;
  for (const DistancePair& d : result.distance_pairs) pairs.push_back(d.pair);
  return pairs;
}

// Distances of the pairs both hold, within kDistanceTolerance (relative, at least absolute).
std::string FirstDistanceDifference(const StepResult& recorded, const StepResult& replayed) {
  std::map<ContactPair, double> replayed_distance;
  for (const DistancePair& d : replayed.distance_pairs) replayed_distance[d.pair] = d.distance;
  for (const DistancePair& d : recorded.distance_pairs) {
    auto it = replayed_distance.find(d.pair);
    if (it == replayed_distance.end()) continue;
    if (std::abs(it->second - d.distance) >
        kDistanceTolerance * std::max(1.0, std::abs(d.distance))) {
      char text[96];
      std::snprintf(text, sizeof(text), ": %.17g recorded, %.17g replayed", d.distance, it->second);
      return "distance of pair " + Describe(d.pair) + text;
    }
  }
  return "";
}

bool Near(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return (a - b).cwiseAbs().maxCoeff() <=
         kDistanceTolerance * std::max(1.0, std::max(a.cwiseAbs().maxCoeff(), 1.0));
}

// The contact geometry of the pairs both hold in the same order (the same contacts and
// distance pairs: otherwise those differences are reported), within kDistanceTolerance.
std::string FirstGeometryDifference(const StepResult& recorded, const StepResult& replayed) {
  if (recorded.contact_geometry.size() == recorded.contacts.size() &&
      replayed.contact_geometry.size() == replayed.contacts.size() &&
      recorded.contacts == replayed.contacts) {
    for (size_t i = 0; i < recorded.contacts.size(); ++i) {
      const ContactGeometry& a = recorded.contact_geometry[i];
      const ContactGeometry& b = replayed.contact_geometry[i];
      bool same = a.num_points == b.num_points && Near(a.normal_a, b.normal_a) &&
                  Near(a.normal_b, b.normal_b);
      for (int k = 0; same && k < a.num_points; ++k) same = Near(a.points[k], b.points[k]);
      if (!same) return "contact geometry of " + Describe(recorded.contacts[i]) + " differs";
    }
  }
  if (recorded.closest_points.size() == recorded.distance_pairs.size() &&
      replayed.closest_points.size() == replayed.distance_pairs.size() &&
      DistancePairsOf(recorded) == DistancePairsOf(replayed)) {
    for (size_t i = 0; i < recorded.closest_points.size(); ++i) {
      if (!Near(recorded.closest_points[i].point_a, replayed.closest_points[i].point_a) ||
          !Near(recorded.closest_points[i].point_b, replayed.closest_points[i].point_b)) {
        return "closest points of " + Describe(recorded.distance_pairs[i].pair) + " differ";
      }
    }
  }
  if (recorded.penetrations.size() == replayed.penetrations.size()) {
    for (size_t i = 0; i < recorded.penetrations.size(); ++i) {
      const Penetration& a = recorded.penetrations[i];
      const Penetration& b = replayed.penetrations[i];
      const ObjectPair objects{a.object_a, a.object_b};
      if (a.object_a != b.object_a || a.object_b != b.object_b || a.closed != b.closed ||
          std::abs(a.depth - b.depth) > kDistanceTolerance * std::max(1.0, a.depth) ||
          !Near(a.point_a, b.point_a) || !Near(a.point_b, b.point_b)) {
        return "penetration of " + Describe(objects) + " differs";
      }
    }
  }
  return "";
}

// A reliable method's PCS holds every contact's triangles (when the reply carries a PCS).
std::string FirstContactOutsidePcs(const StepResult& replayed) {
  if (replayed.pcs_primitives.empty() || !replayed.stats.certificate.guaranteed) return "";
  const auto in_pcs = [&](uint32_t object, uint32_t triangle) {
    auto it = replayed.pcs_primitives.find(object);
    return it != replayed.pcs_primitives.end() &&
           std::binary_search(it->second.begin(), it->second.end(), triangle);
  };
  for (const ContactPair& c : replayed.contacts) {
    if (!in_pcs(c.object_a, c.triangle_a) || !in_pcs(c.object_b, c.triangle_b)) {
      return "replayed contact " + Describe(c) + " is outside the replayed PCS";
    }
  }
  return "";
}

std::string Summary(const StepResult& r) {
  return "contacts " + std::to_string(r.contacts.size()) + ", distance pairs " +
         std::to_string(r.distance_pairs.size()) + ", pcs " + std::to_string(r.pcs_objects.size()) +
         " objects / " + std::to_string(Primitives(r).size()) + " triangles, " + r.stats.method;
}

void CompareResults(const StepResult& recorded, const StepResult& replayed,
                    const CompareOptions& options, StepComparison& out) {
  const bool same_configuration =
      options.same_renderer && recorded.stats.method == replayed.stats.method;
  // Exact outputs: always for the reliable methods; cullide's depend on the renderer.
  const bool exact_required =
      recorded.stats.certificate.guaranteed || same_configuration || options.strict;
  // The PCS and object pairs are exact only for the same configuration on the same renderer.
  const bool pcs_required = same_configuration || options.strict;
  const auto add = [&](bool required, const std::string& difference) {
    if (difference.empty()) return;
    (required ? out.mismatches : out.notes).push_back(difference);
  };
  add(exact_required, FirstDifference("contact", recorded.contacts, replayed.contacts));
  add(exact_required,
      FirstDifference("distance pair", DistancePairsOf(recorded), DistancePairsOf(replayed)));
  add(exact_required, FirstDistanceDifference(recorded, replayed));
  add(exact_required, FirstGeometryDifference(recorded, replayed));
  add(true, FirstContactOutsidePcs(replayed));
  add(pcs_required, FirstDifference("PCS object", recorded.pcs_objects, replayed.pcs_objects));
  add(pcs_required, FirstDifference("PCS triangle", Primitives(recorded), Primitives(replayed)));
  add(pcs_required, FirstDifference("object pair", recorded.object_pairs, replayed.object_pairs));
  if (recorded.stats.method != replayed.stats.method) {
    out.notes.push_back("method " + recorded.stats.method + " recorded, " + replayed.stats.method +
                        " replayed");
  }
  out.summary = Summary(replayed);
}

}  // namespace

StepComparison CompareStep(const Result<StepResult>& recorded, const Result<StepResult>& replayed,
                           const CompareOptions& options) {
  StepComparison out;
  if (!recorded) {
    const ErrorCode code = recorded.error().code;
    // The recording client gave up (its timeout) or lost its daemon: nothing to compare with.
    if (code == ErrorCode::kTimeout || code == ErrorCode::kUnavailable) {
      out.compared = false;
      out.summary = std::string("recorded ") + ToString(code) + ", not compared";
      return out;
    }
    if (replayed) {
      out.mismatches.push_back(std::string("recorded ") + ToString(recorded.error()) +
                               "; the replay succeeded");
    } else if (replayed.error().code != code) {
      out.mismatches.push_back(std::string("recorded ") + ToString(recorded.error()) +
                               "; replayed " + ToString(replayed.error()));
    }
    out.summary = std::string("failed as recorded: ") + ToString(code);
    return out;
  }
  if (!replayed) {
    out.mismatches.push_back("recorded ok; replayed " + ToString(replayed.error()));
    out.summary = "failed";
    return out;
  }
  CompareResults(*recorded, *replayed, options, out);
  return out;
}

}  // namespace far::cli
