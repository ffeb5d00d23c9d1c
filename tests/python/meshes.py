"""Small meshes for the Python tests, as NumPy arrays far.Client and far.Pipeline take."""

import numpy as np


def box(half=0.5):
    """A closed axis-aligned cube centred at the origin: (8, 3) float64, (12, 3) uint32."""
    v = np.array([[x, y, z] for x in (-half, half) for y in (-half, half) for z in (-half, half)],
                 dtype=np.float64)
    t = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]],
                 dtype=np.uint32)
    return v, t


def grid(n=10, size=1.0):
    """A flat n x n grid in z = 0, 2 n^2 triangles: (n+1)^2 vertices."""
    xs = np.linspace(-size / 2, size / 2, n + 1)
    v = np.array([[x, y, 0.0] for y in xs for x in xs], dtype=np.float64)
    t = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            t += [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]]
    return v, np.array(t, dtype=np.uint32)


def contact_set(contacts):
    return {tuple(int(x) for x in row) for row in contacts}
