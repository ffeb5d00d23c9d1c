#pragma once

// A picture of a scene for people (far-snapshot): every object drawn with Lambert
// shading from a camera fitted to the scene's bounds, each triangle coloured by what a step
// found for it. GL stays private, as everywhere in far::gpu.

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "far/base/result.h"
#include "far/model/mesh.h"
#include "far/model/pose.h"

namespace far {

/// What a step found for a triangle, and so its colour (the deepest finding wins).
enum class TriangleMark : uint8_t {
  kPlain,    ///< grey: nothing
  kPcs,      ///< yellow: in the potentially colliding set
  kNear,     ///< orange: in a distance pair (closer than the query's D)
  kContact,  ///< red: in an exact contact pair
};

/// The colour a mark is drawn in (linear RGB in [0, 1], before shading).
Eigen::Vector3f MarkColor(TriangleMark mark);

/// One object to draw: its mesh placed by X_WO, with one mark per triangle (or none: all plain).
struct SnapshotObject {
  const Mesh* mesh = nullptr;
  Pose X_WO;
  std::vector<TriangleMark> marks;
};

/// The picture's size and look.
struct SnapshotOptions {
  int width = 1024, height = 768;  ///< pixels, each in [16, 8192]
  int samples = 4;                 ///< multisampling (clamped to what the driver offers)
  /// Contact triangles hidden behind other geometry are drawn over it, faded, so that no
  /// contact is out of sight.
  bool show_hidden_contacts = true;
};

/// An 8-bit RGB image, rows from top to bottom.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  ///< width * height * 3 bytes
};

/// The background colour of a snapshot (linear RGB in [0, 1]).
Eigen::Vector3f SnapshotBackground();

/// Draws `objects` with the GL context current on this thread (GlContext::Create, or a
/// Pipeline's). The camera looks from above and to the side (z is up) at the centre of the
/// objects' bounding box, from just far enough away that the whole box is in view; the light
/// comes from the camera, both faces of a triangle are lit. Errors: kInvalidArgument (a size
/// out of range, a null mesh, marks that are neither empty nor one per triangle, an index out
/// of range, a non-finite vertex), kInternal (a GL error).
Result<RgbImage> RenderSnapshot(std::span<const SnapshotObject> objects,
                                const SnapshotOptions& options = {});

}  // namespace far
