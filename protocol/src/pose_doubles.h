#pragma once

// A pose as the kPoseDoubles doubles of the ring's records and of recordings (ring_layout.h):
// translation x, y, z, then the rotation quaternion w, x, y, z. The bits go both ways as they
// are: checking a decoded pose is the reader's job.

#include "far/model/pose.h"
#include "far/protocol/ring_layout.h"

namespace far::protocol::internal {

inline void EncodePose(const Pose& X_WO, double out[kPoseDoubles]) {
  out[0] = X_WO.translation.x();
  out[1] = X_WO.translation.y();
  out[2] = X_WO.translation.z();
  out[3] = X_WO.rotation.w();
  out[4] = X_WO.rotation.x();
  out[5] = X_WO.rotation.y();
  out[6] = X_WO.rotation.z();
}

inline Pose DecodePose(const double v[kPoseDoubles]) {
  Pose pose;
  pose.translation = Eigen::Vector3d(v[0], v[1], v[2]);
  pose.rotation = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
  return pose;
}

}  // namespace far::protocol::internal
