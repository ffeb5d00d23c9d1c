#!/usr/bin/python3
"""A simulator loop in Python: a box falls onto a floor and a cloth sags over it; every frame
sends the box's pose and the cloth's vertices (read in place from the NumPy array) and steps.

    deploy/netns-run.sh bash -c 'far-daemon --socket /tmp/far.sock & sleep 2;
        PYTHONPATH=build/release/python /usr/bin/python3 \
            client/python/examples/simulator_loop.py --socket /tmp/far.sock'
    PYTHONPATH=build/release/python /usr/bin/python3 client/python/examples/simulator_loop.py \
        --in-process        # far.Pipeline: no daemon

docs/python.md explains the API this uses.
"""

import argparse
import sys

import numpy as np

import far


def box(half):
    v = np.array([[x, y, z] for x in (-half, half) for y in (-half, half) for z in (-half, half)])
    t = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]],
                 dtype=np.uint32)
    return v, t


def grid(n, size):
    xs = np.linspace(-size / 2, size / 2, n + 1)
    v = np.array([[x, y, 0.0] for y in xs for x in xs])
    t = [[j * (n + 1) + i + d for d in tri]
         for j in range(n) for i in range(n)
         for tri in ([0, 1, n + 2], [0, n + 2, n + 1])]
    return v, np.array(t, dtype=np.uint32)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--socket", default="", help="the daemon's socket (default: daemon 'far')")
    parser.add_argument("--in-process", action="store_true", help="far.Pipeline, no daemon")
    parser.add_argument("--frames", type=int, default=12)
    args = parser.parse_args()

    world = far.Pipeline() if args.in_process else far.Client(
        socket_path=args.socket, client_name="python-simulator", timeout=10.0)
    FLOOR, BOX, CLOTH = 1, 2, 3
    floor_v, floor_t = box(1.0)
    world.add_object(FLOOR, floor_v, floor_t, motion="static", translation=(0, 0, -1.0))
    box_v, box_t = box(0.1)
    world.add_object(BOX, box_v, box_t, motion="rigid", translation=(0, 0, 0.8))
    cloth_v, cloth_t = grid(12, 1.2)
    cloth = cloth_v.copy()  # the array the simulator updates in place, frame after frame
    cloth[:, 2] = 0.5
    world.add_object(CLOTH, cloth, cloth_t, motion="deformable")

    names = {FLOOR: "floor", BOX: "box", CLOTH: "cloth"}
    for frame in range(args.frames):
        z = 0.8 - 0.07 * frame
        world.set_pose(BOX, (0.0, 0.0, z), (1.0, 0.0, 0.0, 0.0))
        r2 = (cloth_v[:, 0] ** 2 + cloth_v[:, 1] ** 2)
        cloth[:, 2] = 0.5 - 0.04 * frame * np.exp(-4 * r2)  # sags in the middle
        world.set_vertices(CLOTH, cloth)
        result = world.step(geometry=True)
        pairs = {}
        for a, _, b, _ in result.contacts:
            pairs[(int(a), int(b))] = pairs.get((int(a), int(b)), 0) + 1
        touching = ", ".join(f"{names[a]}-{names[b]} ({n})" for (a, b), n in sorted(pairs.items()))
        print(f"frame {frame:2d}: box at z={z:.2f}, {len(result.contacts)} contact pairs"
              f"{': ' + touching if touching else ''} [{result.stats['method']}, "
              f"{result.stats['total_ms']:.2f} ms]")
    if not args.in_process:
        world.close()
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except far.Error as e:
        print(f"simulator_loop: {e}", file=sys.stderr)
        sys.exit(1)
