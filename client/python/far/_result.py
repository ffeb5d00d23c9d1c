"""What far.Client.step and far.Pipeline.step return: far::StepResult as NumPy arrays.

Why a plain Python class filled by the C++ binding: both extension modules build the same
object, and its fields are ordinary arrays that a simulator can slice, index and keep after the
next step (they own their memory; nothing refers back into C++).
"""


class Penetrations:
    """far::Penetration, one row per object pair with contacts, sorted by (object_a, object_b):
    objects (P, 2) int64, closed (P,) bool, depth (P,) float64, direction, point_a and point_b
    (P, 3) float64. Only when the step asked for geometry."""

    __slots__ = ("objects", "closed", "depth", "direction", "point_a", "point_b")

    def __init__(self, **fields):
        for name in self.__slots__:
            setattr(self, name, fields[name])

    def __len__(self):
        return len(self.objects)

    def __repr__(self):
        return f"far.Penetrations({len(self)} object pairs)"


class StepResult:
    """One step's answer (far::StepResult). Ids and triangle indices are the scene's.

    contacts         (N, 4) int64: object_a, triangle_a, object_b, triangle_b (sorted)
    distance_pairs   (M, 4) int64, distances (M,) float64: the pairs closer than D
    pcs_objects      (K,) int64; object_pairs (P, 2) int64
    pcs_primitives   dict: object id -> (T,) int64 triangles
    geometry (only when asked, else empty arrays with these shapes):
      contact_point_counts (N,) int64; contact_points (sum of counts, 3) float64, the points of
      contact i after those of contacts 0..i-1; normals_a, normals_b (N, 3); coplanar (N,) bool
      closest_points_a, closest_points_b (M, 3): closest points of distance pair i
      penetrations: far.Penetrations
    stats            dict: method, method_reason, total_ms, stages_ms, counters, certificate
    """

    __slots__ = (
        "contacts",
        "distance_pairs",
        "distances",
        "pcs_objects",
        "object_pairs",
        "pcs_primitives",
        "contact_point_counts",
        "contact_points",
        "normals_a",
        "normals_b",
        "coplanar",
        "closest_points_a",
        "closest_points_b",
        "penetrations",
        "stats",
    )

    def __init__(self, **fields):
        for name in self.__slots__:
            setattr(self, name, fields[name])

    def contact_points_of(self, i):
        """The points of contact i, a (count, 3) view of contact_points."""
        start = int(self.contact_point_counts[:i].sum())
        return self.contact_points[start : start + int(self.contact_point_counts[i])]

    def __repr__(self):
        return (
            f"far.StepResult({len(self.contacts)} contacts, {len(self.distances)} distance pairs, "
            f"{len(self.pcs_objects)} PCS objects, method {self.stats.get('method')!r}, "
            f"{self.stats.get('total_ms', 0):.3g} ms)"
        )
