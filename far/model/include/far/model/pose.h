#pragma once

// Poses and motion kinds: how an object is placed in the world and how it may change.

#include <optional>
#include <string_view>

#include <Eigen/Geometry>

#include "far/base/result.h"

namespace far {

/// How an object may change over the frames of a scene.
enum class Motion {
  kStatic,      ///< never moves: no pose or vertex updates
  kRigid,       ///< moves by pose updates
  kDeformable,  ///< moves by pose and vertex updates (same triangles, new positions)
};

/// Returns the scene-file name of `motion`: "static", "rigid" or "deformable".
const char* ToString(Motion motion);

/// Parses "static", "rigid" or "deformable"; nullopt for anything else.
std::optional<Motion> ParseMotion(std::string_view text);

/// A rigid transform: a rotation, then a translation. Default: identity.
struct Pose {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< unit quaternion

  /// Returns the transform x -> rotation * x + translation.
  Eigen::Isometry3d ToIsometry() const;
};

/// Checks a pose: finite translation, finite rotation with | |q| - 1 | <= kQuaternionTolerance.
/// Errors (kInvalidArgument) start with the field: "translation: not finite",
/// "rotation_wxyz: not finite",
/// "rotation_wxyz: not a unit quaternion (norm 1.7): |norm - 1| must be at most 0.001".
Result<void> CheckPose(const Pose& pose);

/// Returns `pose` with its rotation normalized to unit length. @pre CheckPose(pose).ok()
Pose NormalizedPose(const Pose& pose);

/// CheckPose, then NormalizedPose: what every reader of a pose (scene files, the client
/// library, the daemon's update ring) does, so that a quaternion written with a few decimals
/// is accepted and used as the exact rotation it stands for.
Result<Pose> CheckAndNormalizePose(const Pose& pose);

}  // namespace far
