#pragma once

// Sessions of the healthy scene (ContactSoup(kHealthySeed), 192 triangles) that the limit and
// fair-share tests open beside the sessions they attack, and check that they still get the
// reference contacts.

#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "far/client/client.h"

namespace far::integration {

/// A session of the healthy scene that has stepped once (SmallRequest) with the reference
/// contacts, or nullptr (and a test failure).
std::unique_ptr<client::Client> HealthySession(const std::string& name);

/// One more step of a HealthySession: success when it gives the reference contacts.
::testing::AssertionResult StepsWithTheReference(client::Client& client);

/// The sessions open in the test's daemon (its status, as root sees it), or -1.
int SessionsOpen();

}  // namespace far::integration
