#include "object_listing.h"

#include <algorithm>
#include <tuple>

namespace far::cli {

SceneObjects::SceneObjects(const std::vector<SceneObject>& objects) {
  for (const SceneObject& object : objects) alive_[object.id] = {object.name, object.motion};
}

void SceneObjects::Apply(const FrameUpdate& frame) {
  for (uint32_t id : frame.removals) alive_.erase(id);
  for (const SceneObject& object : frame.additions) {
    alive_[object.id] = {object.name, object.motion};
  }
}

std::string SceneObjects::Name(uint32_t id) const {
  const auto it = alive_.find(id);
  return it == alive_.end() ? std::string() : it->second.name;
}

std::string SceneObjects::Label(uint32_t id) const {
  std::string name = Name(id);
  return name.empty() ? "object " + std::to_string(id) : name;
}

bool SceneObjects::IsStatic(uint32_t id) const {
  const auto it = alive_.find(id);
  return it != alive_.end() && it->second.motion == Motion::kStatic;
}

std::vector<ObjectContact> GroupByObjectPair(const std::vector<ContactPair>& contacts,
                                             const SceneObjects& objects) {
  std::map<std::pair<uint32_t, uint32_t>, size_t> counts;
  for (const ContactPair& c : contacts) ++counts[{c.object_a, c.object_b}];
  std::vector<ObjectContact> grouped;
  for (const auto& [pair, count] : counts) {
    auto [first, second] = pair;
    // "leaf-12 touches tree": what moves is named first.
    if (objects.IsStatic(first) && !objects.IsStatic(second)) std::swap(first, second);
    grouped.push_back({first, second, count});
  }
  std::sort(grouped.begin(), grouped.end(), [](const ObjectContact& x, const ObjectContact& y) {
    return std::tuple(y.triangle_pairs, x.first, x.second) <
           std::tuple(x.triangle_pairs, y.first, y.second);
  });
  return grouped;
}

std::string Describe(const ObjectContact& contact, const SceneObjects& objects) {
  return objects.Label(contact.first) + " touches " + objects.Label(contact.second) + " (" +
         std::to_string(contact.triangle_pairs) + " triangle pair" +
         (contact.triangle_pairs == 1 ? "" : "s") + ")";
}

nlohmann::json ToJson(const ObjectContact& contact, const SceneObjects& objects) {
  return {{"object_a", contact.first},
          {"name_a", objects.Name(contact.first)},
          {"object_b", contact.second},
          {"name_b", objects.Name(contact.second)},
          {"triangle_pairs", contact.triangle_pairs}};
}

std::vector<std::string> DescribeRemovalsAndAdditions(const FrameUpdate& frame,
                                                      const SceneObjects& before) {
  std::vector<std::string> events;
  std::vector<bool> explained(frame.additions.size(), false);
  for (uint32_t id : frame.removals) {
    const std::string name = before.Label(id);
    std::vector<std::string> pieces;
    for (size_t j = 0; j < frame.additions.size(); ++j) {
      const std::string& added = frame.additions[j].name;
      if (!explained[j] && added.size() > name.size() + 1 && added.starts_with(name + "-")) {
        pieces.push_back(added);
        explained[j] = true;
      }
    }
    if (pieces.empty()) {
      events.push_back(name + " disappears");
      continue;
    }
    std::string event = name + " breaks into " + std::to_string(pieces.size()) + " fragment" +
                        (pieces.size() == 1 ? "" : "s") + ":";
    for (size_t k = 0; k < pieces.size(); ++k) event += (k == 0 ? " " : ", ") + pieces[k];
    events.push_back(std::move(event));
  }
  for (size_t j = 0; j < frame.additions.size(); ++j) {
    if (explained[j]) continue;
    const SceneObject& added = frame.additions[j];
    events.push_back((added.name.empty() ? "object " + std::to_string(added.id) : added.name) +
                     " appears");
  }
  return events;
}

}  // namespace far::cli
