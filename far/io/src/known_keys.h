#pragma once

// Strict keys for far-scene/1: a key a reader does not know is an error that names it, its
// JSON path and the closest known key, so a typo ("translaton") never silently becomes a
// default value.

#include <span>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "far/base/result.h"

namespace far::internal {

/// The optimal-string-alignment distance of `a` and `b`: insertions, deletions, substitutions
/// and swaps of two adjacent characters, each costing 1 ("translaton" -> "translation": 1).
size_t EditDistance(std::string_view a, std::string_view b);

/// The known key a person most likely meant by `key`, or "" when none is close: the one at the
/// smallest edit distance when that is at most max(2, its length / 3), else a known key that
/// starts with `key` or that `key` starts with (at least 3 characters shared).
std::string ClosestKey(std::string_view key, std::span<const std::string_view> known);

/// Checks that every key of the JSON object `object` (found at JSON path `where`, "(root)" for
/// the top level) is in `known`; `what` names the level for the message ("a pose"). Error
/// (kParseError): "objects[0].pose.translaton: unknown key 'translaton'; did you mean
/// 'translation'? (keys of a pose: translation, rotation_wxyz, comment)".
Result<void> CheckKnownKeys(const nlohmann::json& object, const std::string& where,
                            const char* what, std::span<const std::string_view> known);

}  // namespace far::internal
