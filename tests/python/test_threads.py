"""Threads: the GIL is released while a call waits for the daemon, and many Python threads
step their own sessions in one process (docs/python.md, "Threads")."""

import os
import signal
import threading
import time

import numpy as np

import far
from meshes import box, contact_set, grid


def test_another_thread_runs_while_one_waits_on_step(own_daemon):
    client = own_daemon.client(timeout=20.0)
    v, t = box()
    client.add_object(1, v, t)
    client.add_object(2, v, t, translation=(0.5, 0, 0))
    assert len(client.step(method="bvh").contacts) > 0
    # A stopped daemon answers nothing: the step waits until SIGCONT, for certain.
    os.kill(own_daemon.process.pid, signal.SIGSTOP)
    in_step, results = threading.Event(), []

    def stepper():
        in_step.set()
        results.append(client.step(method="bvh"))

    thread = threading.Thread(target=stepper)
    thread.start()
    assert in_step.wait(10)
    counted = 0
    deadline = time.monotonic() + 0.5
    while time.monotonic() < deadline:  # Python bytecode on this thread while the other waits
        counted += 1
    assert thread.is_alive() and not results
    os.kill(own_daemon.process.pid, signal.SIGCONT)
    thread.join(20)
    assert not thread.is_alive() and len(results) == 1 and len(results[0].contacts) > 0
    assert counted > 10000, counted
    client.close()


def test_a_connect_that_waits_releases_the_gil(tmp_path):
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.01)

    thread = threading.Thread(target=ticker)
    thread.start()
    start = time.monotonic()
    try:
        far.Client(socket_path=str(tmp_path / "none.sock"), connect_timeout=1.0)
    except far.UnavailableError:
        pass
    end = time.monotonic()
    stop.set()
    thread.join()
    assert end - start >= 0.25  # it waited (retrying with backoff)...
    assert sum(start < t < end for t in ticks) >= 10  # ...and the ticker ran meanwhile


def scene_for(i):
    """Session i's scene: a grid and a box lowered through it by i steps of 0.02 (the deeper,
    the more contacts), so every session has its own answer."""
    v, t = grid(8)
    bv, bt = box(0.15)
    return (v, t), (bv, bt), (0.05 * (i % 4), 0.0, 0.16 - 0.02 * i)


def expected_contacts(i):
    (v, t), (bv, bt), translation = scene_for(i)
    p = far.Pipeline(use_gl=False)
    p.add_object(1, v, t, motion="static")
    p.add_object(2, bv, bt, motion="rigid", translation=translation)
    return contact_set(p.step(method="exact").contacts)


def test_eight_threads_each_step_their_own_session(daemon):
    expected = [expected_contacts(i) for i in range(8)]
    assert len({frozenset(e) for e in expected}) > 4  # the sessions' answers differ
    errors, answers = [], {}
    barrier = threading.Barrier(8)

    def session(i):
        try:
            (v, t), (bv, bt), translation = scene_for(i)
            with daemon.client(name=f"thread-{i}") as client:
                client.add_object(1, v, t, motion="static")
                client.add_object(2, bv, bt, motion="rigid", translation=translation)
                barrier.wait(30)
                got = []
                for step in range(6):
                    method = ("bvh", "far", "auto")[step % 3]
                    got.append(contact_set(client.step(method=method, resolution=128).contacts))
                answers[i] = got
        except Exception as e:  # noqa: BLE001 (reported below, with the thread)
            errors.append((i, repr(e)))

    threads = [threading.Thread(target=session, args=(i,)) for i in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(120)
    assert not errors, errors
    for i in range(8):
        assert len(answers[i]) == 6
        for step, got in enumerate(answers[i]):
            assert got == expected[i], (i, step)


def test_threads_sharing_one_client_take_turns(daemon):
    v, t = box()
    with daemon.client() as client:
        client.add_object(1, v, t)
        client.add_object(2, v, t, translation=(0.5, 0, 0))
        want = contact_set(client.step(method="bvh").contacts)
        errors, counts = [], []

        def worker():
            try:
                for _ in range(5):
                    counts.append(contact_set(client.step(method="bvh").contacts) == want)
            except Exception as e:  # noqa: BLE001
                errors.append(repr(e))

        threads = [threading.Thread(target=worker) for _ in range(4)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(60)
        assert not errors and len(counts) == 20 and all(counts)
