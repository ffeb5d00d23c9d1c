#include "far/model/scene_budget.h"

#include <algorithm>
#include <cstdio>
#include <set>

namespace far {
namespace {

constexpr std::array kKinds = {BudgetKind::kSessions, BudgetKind::kSegmentBytes,
                               BudgetKind::kVertices, BudgetKind::kTriangles};

std::string Printf(const char* format, double value) {
  char text[32];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

std::string UserName(uint32_t user) { return "user " + std::to_string(user); }

// "user 1001 holds 4.0M of its share of 4.0M triangles (8.0M shared by 2 users)"
std::string ShareClause(uint32_t user, int64_t held, int64_t share, int64_t total, int users,
                        BudgetKind kind) {
  return UserName(user) + " holds " + FormatAmount(kind, held) + " of its share of " +
         FormatAmount(kind, share) + " " + ToString(kind) + " (" + FormatAmount(kind, total) +
         " shared by " + std::to_string(users) + (users == 1 ? " user)" : " users)");
}

}  // namespace

const char* ToString(BudgetKind kind) {
  switch (kind) {
    case BudgetKind::kSessions:
      return "sessions";
    case BudgetKind::kSegmentBytes:
      return "bytes of shared memory";
    case BudgetKind::kVertices:
      return "vertices";
    case BudgetKind::kTriangles:
      return "triangles";
  }
  return "?";
}

const char* ConfigKeyOf(BudgetKind kind) {
  switch (kind) {
    case BudgetKind::kSessions:
      return "max_sessions";
    case BudgetKind::kSegmentBytes:
      return "max_segment_bytes_total";
    case BudgetKind::kVertices:
      return "max_vertices_total";
    case BudgetKind::kTriangles:
      return "max_triangles_total";
  }
  return "?";
}

std::string FormatAmount(BudgetKind kind, int64_t amount) {
  const double value = static_cast<double>(amount);
  if (kind == BudgetKind::kSessions) return std::to_string(amount);
  if (kind == BudgetKind::kSegmentBytes) {
    if (amount >= (int64_t{1} << 30)) return Printf("%.1f GiB", value / (1 << 30));
    if (amount >= (int64_t{1} << 20)) return Printf("%.0f MiB", value / (1 << 20));
    if (amount >= (int64_t{1} << 10)) return Printf("%.0f KiB", value / (1 << 10));
    return std::to_string(amount) + " B";
  }
  if (amount < 10'000) return std::to_string(amount);
  if (amount < 1'000'000) return Printf("%.1fK", value / 1e3);
  return Printf("%.1fM", value / 1e6);
}

BudgetAmounts BudgetAmounts::Scene(int64_t vertices, int64_t triangles) {
  BudgetAmounts amounts;
  amounts[BudgetKind::kVertices] = vertices;
  amounts[BudgetKind::kTriangles] = triangles;
  return amounts;
}

BudgetAmounts BudgetAmounts::Session(int64_t segment_bytes) {
  BudgetAmounts amounts;
  amounts[BudgetKind::kSessions] = 1;
  amounts[BudgetKind::kSegmentBytes] = segment_bytes;
  return amounts;
}

int64_t FairShare(int64_t total, int users) {
  return std::max<int64_t>(1, total / std::max(1, users));
}

SharedSceneBudget::SharedSceneBudget(const BudgetAmounts& totals) : totals_(totals) {}

SharedSceneBudget::SharedSceneBudget(int64_t max_vertices, int64_t max_triangles)
    : totals_([&] {
        BudgetAmounts totals = BudgetAmounts::Scene(max_vertices, max_triangles);
        totals[BudgetKind::kSessions] = kUnlimited;
        totals[BudgetKind::kSegmentBytes] = kUnlimited;
        return totals;
      }()) {}

std::map<uint32_t, BudgetAmounts> SharedSceneBudget::HeldByUser() const {
  std::map<uint32_t, BudgetAmounts> by_user;
  for (const auto& [id, holder] : holders_) {
    if (holder.reclaimed) continue;
    BudgetAmounts& sum = by_user[holder.user];
    for (BudgetKind kind : kKinds) sum[kind] += holder.held[kind];
  }
  return by_user;
}

int SharedSceneBudget::UsersLocked() const { return static_cast<int>(HeldByUser().size()); }

Result<std::vector<SharedSceneBudget::Victim>> SharedSceneBudget::Plan(
    uint32_t user, const BudgetAmounts& more) const {
  const auto short_of = [&](BudgetKind kind) { return more[kind] > totals_[kind] - used_[kind]; };
  if (std::none_of(kKinds.begin(), kKinds.end(), short_of)) return std::vector<Victim>{};
  const auto by_user = HeldByUser();
  const auto mine_it = by_user.find(user);
  const BudgetAmounts mine = mine_it == by_user.end() ? BudgetAmounts{} : mine_it->second;
  const int users = static_cast<int>(by_user.size()) + (mine_it == by_user.end() ? 1 : 0);
  // Not free: only a user that stays within its share may have room made for it.
  for (BudgetKind kind : kKinds) {
    if (!short_of(kind)) continue;
    const int64_t share = FairShare(totals_[kind], users);
    if (more[kind] > share - mine[kind]) {
      return MakeError(ErrorCode::kLimitExceeded,
                       std::string(ConfigKeyOf(kind)) + ": " +
                           ShareClause(user, mine[kind], share, totals_[kind], users, kind) + "; " +
                           FormatAmount(kind, more[kind]) + " more would pass its share, and " +
                           FormatAmount(kind, totals_[kind] - used_[kind]) + " are free");
    }
  }
  return PlanReclaim(user, more, users);
}

Result<std::vector<SharedSceneBudget::Victim>> SharedSceneBudget::PlanReclaim(
    uint32_t user, const BudgetAmounts& more, int users) const {
  auto held = HeldByUser();
  BudgetAmounts free;
  for (BudgetKind kind : kKinds) free[kind] = totals_[kind] - used_[kind];
  std::vector<Victim> victims;
  std::set<int64_t> taken;
  for (;;) {
    const auto kind_it = std::find_if(kKinds.begin(), kKinds.end(),
                                      [&](BudgetKind kind) { return more[kind] > free[kind]; });
    if (kind_it == kKinds.end()) return victims;
    const BudgetKind kind = *kind_it;
    const int64_t share = FairShare(totals_[kind], users);
    // The user furthest above its share of this kind...
    uint32_t over_user = 0;
    int64_t most_over = 0;
    for (const auto& [u, amounts] : held) {
      if (u != user && amounts[kind] - share > most_over) {
        over_user = u;
        most_over = amounts[kind] - share;
      }
    }
    if (most_over == 0) {
      return MakeError(ErrorCode::kLimitExceeded,
                       std::string(ConfigKeyOf(kind)) + ": " + FormatAmount(kind, totals_[kind]) +
                           " " + ToString(kind) + " are held by " + std::to_string(users - 1) +
                           " other users, each within its share of " + FormatAmount(kind, share));
    }
    // ...and of its holders of that kind, the one untouched longest.
    const std::pair<const int64_t, Holder>* victim = nullptr;
    for (const auto& entry : holders_) {
      const Holder& h = entry.second;
      if (h.user != over_user || h.reclaimed || h.held[kind] == 0 || taken.count(entry.first))
        continue;
      if (victim == nullptr || h.touched < victim->second.touched) victim = &entry;
    }
    if (victim == nullptr) return MakeError(ErrorCode::kInternal, "budget: no holder to close");
    const std::string size =
        kind == BudgetKind::kSessions
            ? std::string()
            : " (" + FormatAmount(kind, victim->second.held[kind]) + " " + ToString(kind) + ")";
    const std::string why =
        "session closed to make room for " + UserName(user) + ", which is within its share: " +
        ShareClause(over_user, held[over_user][kind], share, totals_[kind], users, kind) +
        ", and of its sessions this one" + size + " had gone longest without a step";
    victims.push_back({victim->first, MakeError(ErrorCode::kLimitExceeded, why)});
    taken.insert(victim->first);
    for (BudgetKind k : kKinds) {
      free[k] += victim->second.held[k];
      held[over_user][k] -= victim->second.held[k];
    }
  }
}

void SharedSceneBudget::Grant(Holder& holder, const BudgetAmounts& more,
                              const std::vector<Victim>& victims) {
  for (const Victim& victim : victims) {
    Holder& closed = holders_.at(victim.holder);
    for (BudgetKind kind : kKinds) used_[kind] -= closed.held[kind];
    closed.held = {};
    closed.reclaimed = true;
  }
  for (BudgetKind kind : kKinds) {
    holder.held[kind] += more[kind];
    used_[kind] += more[kind];
  }
}

void SharedSceneBudget::CallReclaim(const std::vector<Victim>& victims) const {
  if (!reclaim_) return;
  for (const Victim& victim : victims) reclaim_(victim.holder, victim.why);
}

Result<void> SharedSceneBudget::Admit(int64_t holder, uint32_t user, const BudgetAmounts& amounts) {
  std::vector<Victim> victims;
  {
    std::lock_guard lock(mutex_);
    if (holders_.count(holder))
      return MakeError(ErrorCode::kInvalidArgument,
                       "budget: holder " + std::to_string(holder) + " is already admitted");
    auto plan = Plan(user, amounts);
    if (!plan) return plan.error();
    victims = std::move(*plan);
    Holder& admitted = holders_[holder];
    admitted.user = user;
    admitted.touched = ++clock_;
    Grant(admitted, amounts, victims);
  }
  CallReclaim(victims);
  return {};
}

Result<void> SharedSceneBudget::Reserve(int64_t holder, const BudgetAmounts& more) {
  std::vector<Victim> victims;
  {
    std::lock_guard lock(mutex_);
    auto it = holders_.find(holder);
    if (it == holders_.end())
      return MakeError(ErrorCode::kNotFound,
                       "budget: holder " + std::to_string(holder) + " was never admitted");
    if (it->second.reclaimed)
      return MakeError(ErrorCode::kLimitExceeded,
                       "this session was closed to make room for a user within its share");
    auto plan = Plan(it->second.user, more);
    if (!plan) return plan.error();
    victims = std::move(*plan);
    Grant(it->second, more, victims);
  }
  CallReclaim(victims);
  return {};
}

void SharedSceneBudget::Release(int64_t holder, const BudgetAmounts& less) {
  std::lock_guard lock(mutex_);
  auto it = holders_.find(holder);
  if (it == holders_.end() || it->second.reclaimed) return;
  for (BudgetKind kind : kKinds) {
    const int64_t given = std::clamp<int64_t>(less[kind], 0, it->second.held[kind]);
    it->second.held[kind] -= given;
    used_[kind] -= given;
  }
}

void SharedSceneBudget::Leave(int64_t holder) {
  std::lock_guard lock(mutex_);
  auto it = holders_.find(holder);
  if (it == holders_.end()) return;
  for (BudgetKind kind : kKinds) used_[kind] -= it->second.held[kind];
  holders_.erase(it);
}

void SharedSceneBudget::Touch(int64_t holder) {
  std::lock_guard lock(mutex_);
  auto it = holders_.find(holder);
  if (it != holders_.end()) it->second.touched = ++clock_;
}

int64_t SharedSceneBudget::used(BudgetKind kind) const {
  std::lock_guard lock(mutex_);
  return used_[kind];
}

BudgetAmounts SharedSceneBudget::HeldBy(uint32_t user) const {
  std::lock_guard lock(mutex_);
  const auto by_user = HeldByUser();
  auto it = by_user.find(user);
  return it == by_user.end() ? BudgetAmounts{} : it->second;
}

int SharedSceneBudget::users() const {
  std::lock_guard lock(mutex_);
  return UsersLocked();
}

int64_t SharedSceneBudget::ShareOf(uint32_t user, BudgetKind kind) const {
  std::lock_guard lock(mutex_);
  const auto by_user = HeldByUser();
  const int users = static_cast<int>(by_user.size()) + (by_user.count(user) ? 0 : 1);
  return FairShare(totals_[kind], users);
}

}  // namespace far
