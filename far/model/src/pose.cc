// Motion names and the pose rule (finite, unit quaternion within kQuaternionTolerance).

#include "far/model/pose.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "far/base/limits.h"

namespace far {

const char* ToString(Motion motion) {
  switch (motion) {
    case Motion::kStatic:
      return "static";
    case Motion::kRigid:
      return "rigid";
    case Motion::kDeformable:
      return "deformable";
  }
  return "unknown";
}

std::optional<Motion> ParseMotion(std::string_view text) {
  if (text == "static") return Motion::kStatic;
  if (text == "rigid") return Motion::kRigid;
  if (text == "deformable") return Motion::kDeformable;
  return std::nullopt;
}

Eigen::Isometry3d Pose::ToIsometry() const {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = rotation.toRotationMatrix();
  X.translation() = translation;
  return X;
}

Result<void> CheckPose(const Pose& pose) {
  if (!pose.translation.allFinite())
    return MakeError(ErrorCode::kInvalidArgument, "translation: not finite");
  if (!pose.rotation.coeffs().allFinite())
    return MakeError(ErrorCode::kInvalidArgument, "rotation_wxyz: not finite");
  const double norm = pose.rotation.norm();
  if (!(std::abs(norm - 1.0) <= kQuaternionTolerance)) {
    char value[32], tolerance[32];
    std::snprintf(value, sizeof(value), "%.9g", norm);
    std::snprintf(tolerance, sizeof(tolerance), "%g", kQuaternionTolerance);
    return MakeError(ErrorCode::kInvalidArgument,
                     std::string("rotation_wxyz: not a unit quaternion (norm ") + value +
                         "): |norm - 1| must be at most " + tolerance);
  }
  return {};
}

Pose NormalizedPose(const Pose& pose) {
  Pose normalized = pose;
  normalized.rotation.normalize();
  return normalized;
}

Result<Pose> CheckAndNormalizePose(const Pose& pose) {
  if (auto ok = CheckPose(pose); !ok) return ok.error();
  return NormalizedPose(pose);
}

}  // namespace far
