#pragma once

// The largest scene a session may have, and its upload through an update ring smaller than
// the scene: the client writes objects until about half the ring is used, then steps (aabb,
// object PCS: cheap) so that the daemon drains and applies them.

#include <cstdint>

#include "far/base/result.h"
#include "far/client/client.h"
#include "far/model/scene.h"

namespace far::study {

/// far::scenes::ScalingScene (ground, spheres, cloths: contacts everywhere) of at most
/// `max_triangles` triangles (its size is within 2% of the target: the target is 97%).
Scene LargestScene(int64_t max_triangles);

/// Counts triangles and vertices of a scene's objects.
int64_t TriangleCount(const Scene& scene);
int64_t VertexCount(const Scene& scene);

/// Uploads every object of `scene` into the session (ring of `ring_bytes`, the daemon's
/// default 64 MiB), stepping whenever half the ring has been written and once at the end.
Result<void> UploadInParts(client::Client& client, const Scene& scene,
                           uint64_t ring_bytes = 64ull << 20);

}  // namespace far::study
