#pragma once

// Part (g) of the hardening study, issue 41: what a lost LCM datagram costs a client on its
// default step timeout (60 s). A light client's step request or reply is lost on purpose at
// the client library's loss seam (far::client::internal::SetDatagramLoss), and the same client
// steps while this process floods LCM with forged requests; the tables give each step's time
// to complete and how many steps the daemon ran for the steps asked (a step run twice shows).

#include <string>

namespace far::study {

struct LostDatagramSettings {
  std::string daemon;  ///< far-daemon to start
  int trials = 3;      ///< steps per loss case
  double flood_rate = 80'000;
  double flood_seconds = 10;  ///< one flood phase
  int flood_rounds = 2;
  double healthy_rate = 500;  ///< the flooded client's steps per second
};

/// Runs part (g) against a daemon of its own and prints its markdown tables.
void StudyLostDatagrams(const LostDatagramSettings& settings);

}  // namespace far::study
