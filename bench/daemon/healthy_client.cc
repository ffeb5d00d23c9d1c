#include "healthy_client.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "far/scenes/scenes.h"

namespace far::study {

using Clock = std::chrono::steady_clock;

void LatencySample::Merge(const LatencySample& other) {
  ms.insert(ms.end(), other.ms.begin(), other.ms.end());
  errors += other.errors;
  seconds += other.seconds;
  if (first_error.empty()) first_error = other.first_error;
}

Result<std::unique_ptr<HealthyClient>> HealthyClient::Open(const StudyDaemon& daemon,
                                                           const std::string& name,
                                                           std::chrono::milliseconds timeout) {
  std::unique_ptr<HealthyClient> healthy(new HealthyClient());
  auto client = client::Client::Connect(daemon.Options(name, timeout));
  if (!client) return client.error();
  healthy->client_ = std::move(*client);
  // 8 clusters of 128 triangles in a cube of side 2: 1,024 triangles with a few contacts.
  healthy->objects_ = scenes::RandomSoup(17, 8, 128, 2.0, 0.3);
  for (const SceneObject& object : healthy->objects_) {
    if (auto ok = healthy->client_->AddObject(object.id, object.mesh, Motion::kRigid, object.X_WO);
        !ok) {
      return ok.error();
    }
  }
  healthy->request_.method = Method::kBvh;
  healthy->request_.output = Output::kContacts;
  return healthy;
}

// Every object drifts a little, as a simulator's would.
bool HealthyClient::MoveObjects() {
  for (const SceneObject& object : objects_) {
    Pose pose = object.X_WO;
    pose.translation.x() += 0.05 * std::sin(0.01 * step_ + object.id);
    if (!client_->SetPose(object.id, pose)) return false;
  }
  return true;
}

LatencySample HealthyClient::StepFor(double seconds, double steps_per_second) {
  LatencySample sample;
  const auto start = Clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  auto next = start;
  while (Clock::now() < end) {
    if (steps_per_second > 0) {
      std::this_thread::sleep_until(next);
      const auto period = std::chrono::duration_cast<Clock::duration>(
          std::chrono::duration<double>(1 / steps_per_second));
      next = std::max(next + period, Clock::now());
      if (Clock::now() >= end) break;
    }
    ++step_;
    const auto t0 = Clock::now();
    Result<StepResult> result =
        MoveObjects() ? client_->Step(request_)
                      : Result<StepResult>(MakeError(ErrorCode::kUnavailable, "set_pose failed"));
    if (result) {
      sample.ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    } else {
      ++sample.errors;
      if (sample.first_error.empty()) sample.first_error = far::ToString(result.error());
      // A session that is gone stays gone: no point in spinning on it.
      if (result.error().code == ErrorCode::kUnavailable) break;
    }
  }
  sample.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return sample;
}

}  // namespace far::study
