"""far.Pipeline: the in-process pipeline (llvmpipe in CI) against the scene's known answer."""

import threading

import numpy as np
import pytest

import far
from meshes import box, contact_set, grid


@pytest.fixture(scope="module")
def pipeline(scaling_scene):
    p = far.Pipeline()
    p.load_scene(scaling_scene)
    return p


def test_every_reliable_method_finds_the_exact_contacts(pipeline):
    exact = pipeline.step(method="exact")
    assert exact.contacts.dtype == np.int64 and exact.contacts.shape[1] == 4
    assert len(exact.contacts) > 0
    for method in ("bvh", "far", "gpu", "auto"):
        r = pipeline.step(method=method, resolution=256)
        assert contact_set(r.contacts) == contact_set(exact.contacts), method
    assert pipeline.num_objects == 4 and pipeline.num_triangles == 1000
    assert "llvmpipe" in pipeline.gl_renderer or pipeline.gl_renderer


def test_results_are_numpy_arrays_of_the_documented_shapes(pipeline):
    r = pipeline.step(method="bvh")
    n = len(r.contacts)
    assert r.distance_pairs.shape == (0, 4) and r.distances.shape == (0,)
    # No geometry asked: empty arrays of the right shapes.
    assert r.contact_point_counts.shape == (0,) and r.contact_points.shape == (0, 3)
    assert r.normals_a.shape == (0, 3) and r.normals_b.shape == (0, 3) and r.coplanar.shape == (0,)
    assert r.closest_points_a.shape == (0, 3) and len(r.penetrations) == 0
    assert r.penetrations.objects.shape == (0, 2) and r.penetrations.direction.shape == (0, 3)

    g = pipeline.step(method="bvh", distance=0.01, geometry=True)
    assert contact_set(g.contacts) == contact_set(r.contacts)
    m = len(g.distances)
    assert g.distance_pairs.shape == (m, 4) and m >= n
    assert np.all(g.distances >= 0) and np.all(g.distances < 0.01)
    # The geometry arrays are filled as the merged geometry stage fills contact_geometry: their
    # shapes are what this binding promises; their values belong to that stage's tests.
    k = len(g.contact_point_counts)
    assert k in (0, n)
    assert g.contact_points.shape == (int(g.contact_point_counts.sum()), 3)
    assert g.normals_a.shape == (k, 3) and g.normals_b.shape == (k, 3)
    assert g.coplanar.shape == (k,) and g.coplanar.dtype == bool
    assert g.closest_points_a.shape in ((0, 3), (m, 3))
    assert g.closest_points_b.shape == g.closest_points_a.shape
    if k:
        assert g.contact_points_of(0).shape == (g.contact_point_counts[0], 3)


def test_stats_is_a_dict_of_what_ran(pipeline):
    stats = pipeline.step(method="far", resolution=128).stats
    assert stats["method"].startswith("far/")
    assert stats["total_ms"] > 0 and set(stats["stages_ms"]) >= {"update", "exact"}
    assert stats["certificate"]["guaranteed"] is True
    assert stats["certificate"]["levels"][0]["resolution"] == 128
    assert stats["draws"] > 0 and stats["object_pairs"] >= 1


def test_a_deformable_object_moves_by_its_vertices():
    p = far.Pipeline()
    v, t = grid(4)
    bv, bt = box(0.2)
    p.add_object(1, v, t, motion="deformable")
    p.add_object(2, bv, bt, motion="rigid", translation=(0, 0, 1))
    assert len(p.step().contacts) == 0
    lifted = v.copy()
    lifted[:, 2] = 1.0  # the sheet through the box's middle
    p.set_vertices(1, lifted)
    assert len(p.step().contacts) > 0
    p.remove_object(2)
    assert p.num_objects == 1


def test_another_thread_gets_wrong_thread_error(pipeline):
    caught = []

    def other():
        try:
            pipeline.step()
        except far.WrongThreadError as e:
            caught.append(e)

    thread = threading.Thread(target=other)
    thread.start()
    thread.join()
    assert len(caught) == 1 and "thread that made it" in str(caught[0])


def test_library_errors_keep_their_message_and_code(pipeline):
    with pytest.raises(far.InvalidArgumentError, match=r"^resolution: 5 is outside \[8, 8192\]"):
        pipeline.step(resolution=5)
    with pytest.raises(far.InvalidArgumentError, match=r"^method: unknown 'bogus'; the methods"):
        pipeline.step(method="bogus")
    with pytest.raises(far.InvalidArgumentError, match=r"^output: unknown"):
        pipeline.step(output="everything")
    with pytest.raises(far.InvalidArgumentError, match=r"geometry"):
        pipeline.step(output="pcs", geometry=True)
    with pytest.raises(far.NotFoundError) as raised:
        pipeline.remove_object(12345)
    assert raised.value.code == "not_found" and isinstance(raised.value, LookupError)
    with pytest.raises(far.IoError):
        pipeline.load_scene("/nonexistent/scene.json")
    with pytest.raises(far.UnavailableError, match="GL"):
        far.Pipeline(use_gl=False).step(method="far")
