#pragma once

// The daemon-wide budgets a daemon's sessions share (sessions, shared-memory bytes, and the
// vertices and triangles of their scenes), divided fairly between the users that hold them, so
// that no set of clients can make the daemon allocate without bound, and no user can take a
// budget from another:
//
//   - A user's share of a budget is its total divided by the users with sessions open (the
//     user asking counted), and never less than 1: 8M triangles shared by 2 users is 4M each.
//   - A session may grow by what is free, within its share or above it: a user alone may use
//     everything.
//   - When what it asks is not free and its user stays within its share, the room is taken
//     back from users above their share: the sessions of the user furthest above its share
//     (and of those, the one longest without a step first) are closed until it fits. A user
//     above its share holds the part above it on loan; a user within its share always gets it
//     (the sum of the others' shares leaves it room).
//   - Otherwise (its user would pass its share, and it is not free) it is refused, naming the
//     rule: "user 1001 holds 4.0M of its share of 4.0M triangles (8.0M shared by 2 users)".
//
// Every check is per user, not per session: more sessions do not buy a larger share.

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "far/base/result.h"

namespace far {

/// What the users of a daemon share, each with a daemon-wide total.
enum class BudgetKind : uint8_t { kSessions, kSegmentBytes, kVertices, kTriangles };
inline constexpr size_t kNumBudgetKinds = 4;

/// "sessions", "bytes of shared memory", "vertices", "triangles".
const char* ToString(BudgetKind kind);
/// The daemon's config key of the kind's total: "max_sessions", "max_segment_bytes_total",
/// "max_vertices_total", "max_triangles_total".
const char* ConfigKeyOf(BudgetKind kind);
/// An amount for messages: "12" (sessions), "80 MiB" (bytes), "960" or "4.0M" (counts).
std::string FormatAmount(BudgetKind kind, int64_t amount);

/// An amount of each kind (all >= 0).
struct BudgetAmounts {
  std::array<int64_t, kNumBudgetKinds> of{};

  int64_t& operator[](BudgetKind kind) { return of[static_cast<size_t>(kind)]; }
  int64_t operator[](BudgetKind kind) const { return of[static_cast<size_t>(kind)]; }
  /// Vertices and triangles (what a scene holds).
  static BudgetAmounts Scene(int64_t vertices, int64_t triangles);
  /// One session and its segment's bytes.
  static BudgetAmounts Session(int64_t segment_bytes);
};

/// A user's share of `total` when `users` users share it: total / users, at least 1.
int64_t FairShare(int64_t total, int users);

/// The budgets and who holds what. A holder is one session (its id), of one user; a scene model
/// grows and shrinks its holder's vertices and triangles (SceneModel), the daemon admits the
/// holder with its session and its segment. Thread-safe; the reclaim callback is called with
/// no lock held.
class SharedSceneBudget {
 public:
  static constexpr int64_t kUnlimited = std::numeric_limits<int64_t>::max();

  /// Budgets of these totals (>= 1 each).
  explicit SharedSceneBudget(const BudgetAmounts& totals);
  /// Vertices and triangles only (sessions and bytes unlimited).
  SharedSceneBudget(int64_t max_vertices, int64_t max_triangles);

  /// Called for every holder closed to make room (the daemon closes its session and tells its
  /// client `why`, kLimitExceeded). Set before any holder is admitted.
  using Reclaim = std::function<void(int64_t holder, const Error& why)>;
  void OnReclaim(Reclaim reclaim) { reclaim_ = std::move(reclaim); }

  /// Admits a new holder of `user` holding `amounts` from the start, by the rule above (may
  /// close holders of users above their share). Errors: kLimitExceeded naming the kind, the
  /// user, its share and the users sharing it; kInvalidArgument when `holder` is already here.
  Result<void> Admit(int64_t holder, uint32_t user, const BudgetAmounts& amounts);
  /// Grows a holder by `more`, by the rule above. Errors: kLimitExceeded as Admit's, and when
  /// the holder was closed to make room; kNotFound for a holder never admitted (or gone).
  Result<void> Reserve(int64_t holder, const BudgetAmounts& more);
  /// Gives back amounts the holder reserved before (nothing for a holder closed or gone).
  void Release(int64_t holder, const BudgetAmounts& less);
  /// Gives back everything the holder holds and forgets it (its session's memory is freed).
  void Leave(int64_t holder);
  /// Notes that the holder stepped: holders of one user are closed longest-untouched first.
  void Touch(int64_t holder);

  int64_t total(BudgetKind kind) const { return totals_[kind]; }
  /// Held by every holder, of one kind.
  int64_t used(BudgetKind kind) const;
  /// Held by one user's holders.
  BudgetAmounts HeldBy(uint32_t user) const;
  /// Users with at least one holder (not closed to make room).
  int users() const;
  /// A user's share now (FairShare with users(), or users() + 1 for a user that holds none).
  int64_t ShareOf(uint32_t user, BudgetKind kind) const;

  int64_t vertices() const { return used(BudgetKind::kVertices); }
  int64_t triangles() const { return used(BudgetKind::kTriangles); }
  int64_t max_vertices() const { return total(BudgetKind::kVertices); }
  int64_t max_triangles() const { return total(BudgetKind::kTriangles); }

 private:
  struct Holder {
    uint32_t user = 0;
    BudgetAmounts held;
    uint64_t touched = 0;  // the clock when it last stepped (or was admitted)
    bool reclaimed = false;
  };
  struct Victim {
    int64_t holder;
    Error why;
  };
  // What growing `user`'s holder by `more` takes: nothing, or the holders to close first.
  // Errors: the refusal. Under mutex_.
  Result<std::vector<Victim>> Plan(uint32_t user, const BudgetAmounts& more) const;
  Result<std::vector<Victim>> PlanReclaim(uint32_t user, const BudgetAmounts& more,
                                          int users) const;
  // Grants `more` to `holder` after closing the victims' holders. Under mutex_.
  void Grant(Holder& holder, const BudgetAmounts& more, const std::vector<Victim>& victims);
  void CallReclaim(const std::vector<Victim>& victims) const;
  std::map<uint32_t, BudgetAmounts> HeldByUser() const;  // under mutex_
  int UsersLocked() const;                               // under mutex_

  const BudgetAmounts totals_;
  Reclaim reclaim_;
  mutable std::mutex mutex_;
  std::map<int64_t, Holder> holders_;
  BudgetAmounts used_;
  uint64_t clock_ = 0;
};

}  // namespace far
