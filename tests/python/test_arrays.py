"""NumPy arguments: the dtype, shape and layout rules (docs/python.md, "Arrays"), without a
daemon. far.Pipeline(use_gl=False) and far.Client share the checks (client/python/src/arrays.cc);
test_client.py shows the same errors from a far.Client."""

import numpy as np
import pytest

import far
from meshes import box, grid


@pytest.fixture
def pipeline():
    p = far.Pipeline(use_gl=False)
    v, t = grid(2)
    p.add_object(1, v, t, motion="deformable")
    return p


def test_float64_rows_are_read_in_place():
    v = np.zeros((5, 3))
    assert far._client._vector3_span_address(v) == v.ctypes.data
    rows = np.zeros((10, 3))[2:7]  # contiguous rows of a larger array: still no copy
    assert far._client._vector3_span_address(rows) == rows.ctypes.data
    empty = np.zeros((0, 3))
    assert far._client._vector3_span_address(empty) == 0  # an empty span


@pytest.mark.parametrize(
    "bad, words",
    [
        (np.zeros((9, 3), dtype=np.float32), "float32"),
        (np.zeros((9, 3), dtype=np.int64), "int64"),
        (np.zeros((9, 3), dtype=">f8"), "non-native"),
        (np.zeros((9, 4)), "shape (9, 4)"),
        (np.zeros(27), "shape (27,)"),
        (np.zeros((3, 9, 3)), "shape (3, 9, 3)"),
        (np.zeros((18, 3))[::2], "non-contiguous"),
        (np.zeros((9, 6))[:, :3], "non-contiguous"),
        (np.asfortranarray(np.zeros((9, 3))), "non-contiguous"),
        ([[0.0, 0.0, 0.0]] * 9, "got list"),
    ],
)
def test_vertices_of_the_wrong_kind_are_refused_naming_the_argument(pipeline, bad, words):
    if words == "non-native":
        words = ">f8"
    with pytest.raises(far.InvalidArgumentError, match=r"^vertices: expected a C-contiguous numpy "
                       r"float64 array of shape \(N, 3\)") as raised:
        pipeline.set_vertices(1, bad)
    assert words in str(raised.value) or words.replace(">f8", "float64") in str(raised.value)
    assert raised.value.code == "invalid_argument"
    assert isinstance(raised.value, far.Error) and isinstance(raised.value, ValueError)


def test_triangles_must_be_uint32_rows():
    p = far.Pipeline(use_gl=False)
    v, t = box()
    for bad in (t.astype(np.int64), t.astype(np.int32), t.reshape(-1), t.T):
        with pytest.raises(far.InvalidArgumentError, match=r"^triangles: "):
            p.add_object(1, v, bad)
    with pytest.raises(far.InvalidArgumentError, match=r"^vertices: .*float32"):
        p.add_object(1, v.astype(np.float32), t)
    p.add_object(1, v, t)
    assert p.num_objects == 1


def test_poses_take_numbers_and_float64_arrays_only():
    p = far.Pipeline(use_gl=False)
    v, t = box()
    p.add_object(1, v, t, translation=np.array([1.0, 2, 3]), rotation_wxyz=[1, 0, 0, 0])
    p.set_pose(1, (0.5, 0, 0), np.array([0.0, 1.0, 0.0, 0.0]))
    with pytest.raises(far.InvalidArgumentError, match=r"^translation: expected 3 numbers.*float32"):
        p.set_pose(1, np.zeros(3, dtype=np.float32))
    with pytest.raises(far.InvalidArgumentError, match=r"^translation: expected 3 numbers, got 2"):
        p.set_pose(1, (0, 0))
    with pytest.raises(far.InvalidArgumentError, match=r"^rotation_wxyz: expected 4 numbers"):
        p.set_pose(1, (0, 0, 0), (1, 0, 0))
    with pytest.raises(far.InvalidArgumentError, match=r"^rotation_wxyz: .*element 0 is True"):
        p.set_pose(1, (0, 0, 0), (True, 0, 0, 0))
    # The C++ library's own check (far::CheckPose), its message unchanged.
    with pytest.raises(far.InvalidArgumentError, match=r"not a unit quaternion"):
        p.set_pose(1, (0, 0, 0), (2, 0, 0, 0))
    with pytest.raises(far.InvalidArgumentError, match=r"^motion: unknown 'flying'"):
        p.add_object(2, v, t, motion="flying")
