#pragma once

// Scenes with known contacts for the integration tests, their brute-force reference answers,
// and the "healthy client" check every bad-input test ends with.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "far/model/contact_pair.h"
#include "far/model/scene.h"

namespace far::integration {

/// A random triangle soup with several contacts (far::scenes::RandomSoup: 8 rigid objects of
/// 24 triangles in a cube of side 1.5 around `origin`, ids 1, 4, 7, ...), each object with a
/// mesh_path "obj_<id>.obj" so that WriteScene can write it.
std::vector<SceneObject> ContactSoup(uint64_t seed,
                                     const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// The seed of the scene the healthy client uploads.
inline constexpr uint64_t kHealthySeed = 11;

/// Brute-force reference contacts of `objects` (BruteForceReference, sorted).
std::vector<ContactPair> ReferenceContacts(const std::vector<SceneObject>& objects);
/// Brute-force reference distance pairs (ids only, sorted) within `distance`.
std::vector<ContactPair> ReferenceDistancePairs(const std::vector<SceneObject>& objects,
                                                double distance);

/// Connects a new far::client::Client named `name`, uploads ContactSoup(kHealthySeed), runs a
/// FAR step at resolution 128 and checks that its contacts equal the reference (non-empty).
/// The daemon is still serving well-behaved clients.
::testing::AssertionResult HealthyClientSteps(const std::string& name = "healthy");

/// A mesh of `n` triangles in a row along x (3n vertices), each the unit right triangle moved by
/// 2 units: no two touch.
Mesh TriangleRow(int n);

/// A flat fan of `n` triangles around vertex 0 (n + 2 vertices).
Mesh TriangleFan(int n);

/// A flat square grid in the z = 0 plane: `n` x `n` cells of side 1 / n, two triangles each.
Mesh FlatGrid(int n);

/// Prints contacts as "[a,ta,b,tb] ..." (at most `limit`) for failure messages.
std::string ToString(const std::vector<ContactPair>& pairs, size_t limit = 20);

}  // namespace far::integration
