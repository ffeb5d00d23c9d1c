#include "known_keys.h"

#include <algorithm>
#include <vector>

#include "io_util.h"

namespace far::internal {

size_t EditDistance(std::string_view a, std::string_view b) {
  // Three rows of the dynamic programme: two back for the adjacent swap.
  std::vector<size_t> before(b.size() + 1), previous(b.size() + 1), current(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t substitution = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitution});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        current[j] = std::min(current[j], before[j - 2] + 1);
      }
    }
    std::swap(before, previous);
    std::swap(previous, current);
  }
  return previous[b.size()];
}

std::string ClosestKey(std::string_view key, std::span<const std::string_view> known) {
  std::string_view best;
  size_t best_distance = SIZE_MAX;
  for (std::string_view candidate : known) {
    const size_t distance = EditDistance(key, candidate);
    if (distance < best_distance) {
      best = candidate;
      best_distance = distance;
    }
  }
  if (!best.empty() && best_distance <= std::max<size_t>(2, best.size() / 3)) {
    return std::string(best);
  }
  // "rotation" for "rotation_wxyz": too far by edits, but plainly meant.
  for (std::string_view candidate : known) {
    const size_t shared = std::min(key.size(), candidate.size());
    if (shared >= 3 && key.substr(0, shared) == candidate.substr(0, shared)) {
      return std::string(candidate);
    }
  }
  return "";
}

Result<void> CheckKnownKeys(const nlohmann::json& object, const std::string& where,
                            const char* what, std::span<const std::string_view> known) {
  for (const auto& item : object.items()) {
    const std::string& key = item.key();
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    const std::string quoted = Quote(key);
    // The path names the key itself; the quotes come off the shown text.
    const std::string path =
        (where == "(root)" ? "" : where + ".") + quoted.substr(1, quoted.size() - 2);
    std::string message = path + ": unknown key " + quoted;
    if (const std::string closest = ClosestKey(key, known); !closest.empty()) {
      message += "; did you mean '" + closest + "'?";
    }
    message += std::string(" (keys of ") + what + ":";
    const char* separator = " ";
    for (std::string_view k : known) {
      message += separator + std::string(k);
      separator = ", ";
    }
    message += ")";
    return MakeError(ErrorCode::kParseError, message);
  }
  return {};
}

}  // namespace far::internal
