#pragma once
// What collided, in words: objects named as the scene file names them, contact pairs grouped by
// object pair ("leaf-12 touches tree (37 triangle pairs)"), and what a frame removed and added
// ("vase breaks into 4 fragments: ..."). Shared by play and snapshot.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "far/model/contact_pair.h"
#include "far/model/scene.h"

namespace far::cli {

/// The objects alive at the current step of a scene, by id: their names and motions.
class SceneObjects {
 public:
  explicit SceneObjects(const std::vector<SceneObject>& objects);
  /// Follows a frame's removals and additions (apply before the step the frame leads to).
  void Apply(const FrameUpdate& frame);
  /// The object's name; "" when it has none (or is not known).
  std::string Name(uint32_t id) const;
  /// The object's name, or "object <id>" when it has none (or is not known).
  std::string Label(uint32_t id) const;
  /// True for a static object (known and static).
  bool IsStatic(uint32_t id) const;

 private:
  struct Known {
    std::string name;
    Motion motion = Motion::kStatic;
  };
  std::map<uint32_t, Known> alive_;
};

/// Two objects in contact and how many of their triangle pairs intersect. `first` is the one
/// named first: the moving one when the other is static, else the smaller id.
struct ObjectContact {
  uint32_t first = 0, second = 0;
  size_t triangle_pairs = 0;
};

/// Contact pairs grouped by object pair: most triangle pairs first, then by ids.
std::vector<ObjectContact> GroupByObjectPair(const std::vector<ContactPair>& contacts,
                                             const SceneObjects& objects);

/// "leaf-12 touches tree (37 triangle pairs)" ("1 triangle pair" for one).
std::string Describe(const ObjectContact& contact, const SceneObjects& objects);

/// The same as JSON: {"object_a", "name_a", "object_b", "name_b", "triangle_pairs"} with a the
/// first object named (names are "" for unnamed objects).
nlohmann::json ToJson(const ObjectContact& contact, const SceneObjects& objects);

/// What `frame` removes and adds, one sentence per event, named with `before` (the objects
/// before the frame): an object removed while objects named "<its name>-..." are added
/// "breaks into N fragments: a, b, ...", others "disappears" / "appears". Empty when the frame
/// removes and adds nothing.
std::vector<std::string> DescribeRemovalsAndAdditions(const FrameUpdate& frame,
                                                      const SceneObjects& before);

}  // namespace far::cli
