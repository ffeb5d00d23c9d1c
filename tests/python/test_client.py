"""far.Client against a real far-daemon (in this test's network namespace; conftest.py)."""

import json
import os
import subprocess

import numpy as np
import pytest

import far
from meshes import box, contact_set, grid


def far_client_collide(daemon, scene, *args):
    """The C++ client's answer: far-client collide's JSON."""
    out = subprocess.run([os.environ["FAR_CLIENT_PATH"], "--socket", daemon.socket, "collide",
                          scene, *args], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def test_same_contacts_as_the_cpp_client_and_the_pipeline(daemon, scaling_scene):
    with daemon.client() as client:
        client.load_scene(scaling_scene)
        for method in ("bvh", "far"):
            r = client.step(method=method, resolution=256)
            cpp = far_client_collide(daemon, scaling_scene, "--method", method,
                                     "--resolution", "256")
            assert contact_set(r.contacts) == {tuple(c) for c in cpp["contacts"]}, method
            assert len(r.contacts) > 0
        d = client.step(method="bvh", distance=0.01)
        cpp = far_client_collide(daemon, scaling_scene, "--method", "bvh", "--distance", "0.01")
        assert contact_set(d.distance_pairs) == {tuple(p[:4]) for p in cpp["distance_pairs"]}
        np.testing.assert_allclose(d.distances, [p[4] for p in cpp["distance_pairs"]])
    pipeline = far.Pipeline(use_gl=False)
    pipeline.load_scene(scaling_scene)
    assert contact_set(pipeline.step(method="bvh").contacts) == contact_set(r.contacts)


def test_objects_poses_and_vertices_from_numpy(daemon):
    v, t = grid(6)
    bv, bt = box(0.2)
    with daemon.client() as client:
        assert client.session_id > 0
        client.add_object(1, v, t, motion="deformable")
        client.add_object(2, bv, bt, motion="rigid", translation=(0, 0, 1))
        client.add_object(3, bv, bt, motion="static", translation=(5, 5, 5))
        assert len(client.step().contacts) == 0
        client.set_pose(2, (0, 0, 0.1), (1, 0, 0, 0))
        touching = client.step(method="bvh")
        assert set(touching.contacts[:, 0]) == {1} and set(touching.contacts[:, 2]) == {2}
        lifted = v.copy()
        lifted[:, 2] = 2.0
        client.set_vertices(1, lifted)  # in place from the array (docs/python.md)
        assert len(client.step().contacts) == 0
        client.remove_object(2)
        r = client.step(output="object-pcs")
        assert r.contacts.shape == (0, 4)
        # Wrong arrays are refused before anything is sent, naming the argument.
        with pytest.raises(far.InvalidArgumentError, match=r"^vertices: .*non-contiguous"):
            client.set_vertices(1, np.zeros((len(v) * 2, 3))[::2])
        with pytest.raises(far.InvalidArgumentError, match=r"^triangles: .*int64"):
            client.add_object(4, bv, bt.astype(np.int64))
        # The daemon's errors, by code, with the library's message: updates take effect at
        # the next step, which answers for them.
        client.set_pose(3, (0, 0, 0))
        with pytest.raises(far.Error, match="static") as raised:
            client.step()
        assert type(raised.value) is far.InvalidArgumentError, repr(raised.value)
        client.remove_object(99)
        with pytest.raises(far.NotFoundError, match="99"):
            client.step()
        client.close()
        with pytest.raises(far.UnavailableError):
            client.step()


def test_geometry_arrays_have_their_shapes(daemon, scaling_scene):
    with daemon.client() as client:
        client.load_scene(scaling_scene)
        plain = client.step(method="bvh")
        assert plain.contact_point_counts.shape == (0,) and plain.contact_points.shape == (0, 3)
        assert plain.closest_points_a.shape == (0, 3) and len(plain.penetrations) == 0
        g = client.step(method="bvh", distance=0.01, geometry=True)
        n, m, k = len(g.contacts), len(g.distances), len(g.contact_point_counts)
        assert k in (0, n) and g.normals_a.shape == (k, 3) and g.coplanar.shape == (k,)
        assert g.contact_points.shape == (int(g.contact_point_counts.sum()), 3)
        assert g.closest_points_a.shape in ((0, 3), (m, 3))
        assert g.penetrations.depth.shape == (len(g.penetrations),)


def test_stats_and_status_are_dicts(daemon, scaling_scene):
    with daemon.client(name="stats-test") as client:
        client.load_scene(scaling_scene)
        stats = client.step(method="bvh").stats
        assert stats["method"] == "bvh" and stats["total_ms"] > 0
        assert "exact" in stats["stages_ms"] and stats["certificate"]["guaranteed"]
        status = far.Client.status(socket_path=daemon.socket)
        assert status["sessions_open"] >= 1 and status["steps_total"] >= 1
        assert "stats-test" in [s["client_name"] for s in status["sessions"]]
        assert status["gl_renderer"]


def test_no_daemon_is_unavailable_with_the_library_message(tmp_path):
    missing = str(tmp_path / "none.sock")
    with pytest.raises(far.UnavailableError, match="no far-daemon") as raised:
        far.Client(socket_path=missing, connect_timeout=0.2)
    assert raised.value.code == "unavailable"
    with pytest.raises(far.UnavailableError):
        far.Client.status(socket_path=missing, connect_timeout=0.1)
    with pytest.raises(far.InvalidArgumentError, match="^timeout: "):
        far.Client(socket_path=missing, timeout=-1)
    with pytest.raises(far.InvalidArgumentError, match="^hear_timeout: expected seconds"):
        far.Client(socket_path=missing, hear_timeout="1s")
    with pytest.raises(TypeError):
        far.Client(missing)  # every option is a keyword


def test_step_options_are_far_clients(daemon, scaling_scene):
    with daemon.client() as client:
        client.load_scene(scaling_scene)
        pcs = client.step(method="far", mechanism="occlusion-query", resolution=128,
                          depth_format="depth32f", subobject_size=2, output="pcs")
        assert pcs.stats["method"] == "far/occlusion-query/128"
        assert len(pcs.pcs_objects) == 4 and pcs.contacts.shape == (0, 4)
        assert all(a.dtype == np.int64 for a in pcs.pcs_primitives.values())
        pairs = client.step(method="bvh", output="pairs")
        assert pairs.object_pairs.shape[1] == 2 and len(pairs.object_pairs) >= 1
        with pytest.raises(far.InvalidArgumentError, match="^depth_format: unknown"):
            client.step(depth_format="depth8")
