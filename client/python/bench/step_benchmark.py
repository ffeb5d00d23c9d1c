#!/usr/bin/python3
"""far.Client against the C++ client (far::client::Client): time per simulator step through one
far-daemon, on the same 1K-triangle scene (`far-client make-scene --kind scaling --triangles
1000`: a static ground, two rigid spheres, a cloth; about a hundred contacts). A step is what a
simulator does each frame: a pose for every rigid object, then step() (auto, contacts), waiting
for the reply. The C++ side is far_python_bench_peer (bench/cpp_peer.cc), a session of its own
that runs the same steps on command, so the two clients' rounds interleave in one run (the
order alternates round by round) under the same daemon and machine load.

Not a test (nothing asserts a time). Inside a private network namespace (LCM multicast):
    cmake --build --preset release --target far_python_client far_python_bench_peer far-daemon far-client
    deploy/netns-run.sh /usr/bin/python3 client/python/bench/step_benchmark.py build/release
"""

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time


def quartiles(values):
    q = statistics.quantiles(values, n=4)
    return q[0], statistics.median(values), q[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("build", help="the build folder (build/release)")
    parser.add_argument("--rounds", type=int, default=30, help="measured rounds per client")
    parser.add_argument("--steps", type=int, default=20, help="steps per round")
    args = parser.parse_args()
    if os.environ.get("FAR_IN_NETNS") != "1":
        sys.exit("step_benchmark: run it inside deploy/netns-run.sh (LCM multicast)")
    build = os.path.abspath(args.build)
    sys.path.insert(0, os.path.join(build, "python"))
    import far  # noqa: E402 (from the build tree given)

    work = tempfile.TemporaryDirectory(prefix="far-python-bench-")
    scene_path = os.path.join(work.name, "scene.json")
    subprocess.run([os.path.join(build, "tools/far-client/far-client"), "make-scene", scene_path,
                    "--kind", "scaling", "--triangles", "1000", "--frames", "2"],
                   check=True, capture_output=True)
    socket = os.path.join(work.name, "far.sock")
    log = open(os.path.join(work.name, "daemon.log"), "wb")
    daemon = subprocess.Popen([os.path.join(build, "server/far-daemon"), "--socket", socket],
                              stdout=log, stderr=subprocess.STDOUT)
    peer = None
    try:
        status = far.Client.status(socket_path=socket, connect_timeout=60)
        client = far.Client(socket_path=socket, client_name="bench-python")
        client.load_scene(scene_path)
        with open(scene_path) as f:
            rigid = [(o["id"], o["pose"]["translation"], o["pose"]["rotation_wxyz"])
                     for o in json.load(f)["objects"] if o["motion"] == "rigid"]
        peer = subprocess.Popen([os.path.join(build, "client/python/far_python_bench_peer"),
                                 socket, scene_path], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, text=True)
        assert peer.stdout.readline().strip() == "ready"
        step_index = [0]

        def python_round(k):
            times, contacts = [], []
            for _ in range(k):
                start = time.perf_counter()
                dz = 0.002 * (step_index[0] % 10)  # as cpp_peer.cc
                for oid, t, q in rigid:
                    client.set_pose(oid, (t[0], t[1], t[2] + dz), q)
                r = client.step()
                times.append((time.perf_counter() - start) * 1e6)
                contacts.append(len(r.contacts))
                step_index[0] += 1
            return times, contacts

        def cpp_round(k):
            peer.stdin.write(f"steps {k}\n")
            peer.stdin.flush()
            fields = peer.stdout.readline().split()
            return [float(x) for x in fields[0::2]], [int(x) for x in fields[1::2]]

        python_round(args.steps), cpp_round(args.steps)  # warm-up: auto calibrates, caches fill
        py_times, cpp_times, ratios = [], [], []
        py_contacts, cpp_contacts = set(), set()
        for round_index in range(args.rounds):
            order = (python_round, cpp_round) if round_index % 2 == 0 else (cpp_round, python_round)
            got = {}
            for run in order:
                got[run] = run(args.steps)
            py_times += got[python_round][0]
            cpp_times += got[cpp_round][0]
            py_contacts.update(got[python_round][1])
            cpp_contacts.update(got[cpp_round][1])
            ratios.append(statistics.median(got[python_round][0]) /
                          statistics.median(got[cpp_round][0]))
        py_q, cpp_q, ratio_q = quartiles(py_times), quartiles(cpp_times), quartiles(ratios)
        print(f"machine: nproc {os.cpu_count()}, GL_RENDERER {status['gl_renderer']}")
        print(f"scene: 1,000 triangles, {len(rigid)} rigid objects posed per step; "
              f"{args.rounds} rounds x {args.steps} steps per client, interleaved")
        print(f"contacts per step: python {sorted(py_contacts)}, c++ {sorted(cpp_contacts)}")
        print(f"python far.Client  median {py_q[1]:8.1f} us  [p25 {py_q[0]:.1f} - p75 {py_q[2]:.1f}]")
        print(f"c++ client         median {cpp_q[1]:8.1f} us  [p25 {cpp_q[0]:.1f} - p75 {cpp_q[2]:.1f}]")
        print(f"python / c++ (per-round medians): median {ratio_q[1]:.3f} "
              f"[p25 {ratio_q[0]:.3f} - p75 {ratio_q[2]:.3f}]; of all steps' medians "
              f"{py_q[1] / cpp_q[1]:.3f}")
        client.close()
    finally:
        if peer:
            peer.stdin.close()
            peer.wait(10)
        daemon.send_signal(signal.SIGTERM)
        daemon.wait(10)
        log.close()


if __name__ == "__main__":
    main()
