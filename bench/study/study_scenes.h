#pragma once

// far-study's scenes. Every scene is a far::Scene: the objects at the unmeasured warm-up step 0,
// then one FrameUpdate per measured step, so that every configuration is driven the same way
// (Pipeline::Apply: removals, additions, poses, vertices) whatever the scene changes.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "far/base/result.h"
#include "far/model/scene.h"

namespace far_study {

/// Which configurations a scene gets (study_run.h) and which bars it counts for.
enum class Family {
  kSmall,    ///< soup, bunnies, leaves, bunnies-fine: every GPU configuration
  kPaper,    ///< the paper-scale workloads: a reduced GPU set, the distance pass
  kScaling,  ///< ScalingScene at one size: CPU methods, GPU only up to a size
};

/// What moves; the CPU path's bar has a target per kind.
enum class Kind { kRigid, kDeformable, kBreaking };

std::string_view ToString(Family family);
std::string_view ToString(Kind kind);

struct StudyScene {
  std::string name, description;
  Family family = Family::kSmall;
  Kind kind = Kind::kRigid;
  far::Scene scene;       ///< frames[k] is applied before measured step k + 1
  int64_t triangles = 0;  ///< at step 0
  /// The size asked for: scaling's target (its scene is within 2% of it), else `triangles`.
  /// The scaling limits (--scaling-gpu-max, --scaling-reference-max) compare against it.
  int64_t nominal_triangles = 0;
  double diagonal = 0;     ///< of the world bounding box at step 0 (D is a fraction of it)
  bool far_only = false;   ///< bunnies-fine: FAR at the primary resolution only
  std::string break_note;  ///< breaking: at which measured step the break happens
  int break_step = 0;      ///< breaking: that measured step; 0 for the other scenes
  /// Measured steps the reference must check even when it runs on a few steps only
  /// (--reference-steps): breaking's break and the step after it.
  std::vector<int> key_steps;
};

/// Sizes and steps of the scenes.
struct SceneOptions {
  int steps = 4;  ///< measured steps of every scene but bunnies-fine
  int fine_steps = 2;
  std::string bunny_path;
  int bunny_subdivisions = 0;              ///< soup-era bunnies: midpoint subdivisions
  int fine_extra_subdivisions = 1;         ///< bunnies-fine: beyond bunny_subdivisions
  int paper_bunny_refinement = 5;          ///< paper-bunnies: RefineMesh n (91,850 triangles for 5)
  int breaking_static_triangles = 100000;  ///< breaking: the terrain (at least)
  int breaking_rigid_triangles = 35000;    ///< breaking: the vase (at least)
  int soup_objects = 32, soup_triangles = 48;
  int leaves = 60, leaf_cells = 6;
};

/// The fixed scene names; "scaling-<triangles>" is the scaling family at one size.
const std::vector<std::string>& FixedSceneNames();
bool IsKnownScene(const std::string& name);

/// Builds the scene called `name`. Errors: the bunny mesh cannot be read; unknown name.
far::Result<StudyScene> MakeStudyScene(const std::string& name, const SceneOptions& options);

}  // namespace far_study
