"""Fixtures of the Python tests (tests/python, run by ctest: tests/python/tests_python.cmake).

Daemon tests start far-daemon the way the C++ integration tests do (tests/integration/
daemon_process.cc): their own socket in a temporary folder, the default LCM URL, waiting until
it answers a status request, SIGTERM at the end with exit status 0 expected and the log
printed when it is not. ctest runs every file inside deploy/netns-run.sh, a private network
namespace: a daemon is started only there (FAR_IN_NETNS=1), so no test sends a datagram
anywhere but that namespace's loopback.
"""

import os
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))

import far  # noqa: E402


def cost_cache_flags():
    """The tree's shared GPU cost cache (ctest sets FAR_TEST_GPU_COST_CACHE): the first daemon
    measures auto's GPU cost, the others start without the probe (docs/testing.md)."""
    path = os.environ.get("FAR_TEST_GPU_COST_CACHE")
    return ["--gpu-cost-cache", path] if path else []


class Daemon:
    def __init__(self, args=()):
        path = os.environ.get("FAR_DAEMON_PATH")
        if not path:
            pytest.fail("FAR_DAEMON_PATH is not set (ctest sets it: tests/python/tests_python.cmake)")
        if os.environ.get("FAR_IN_NETNS") != "1":
            pytest.fail("daemon tests run inside deploy/netns-run.sh (LCM multicast stays on a "
                        "private loopback); run them through ctest or netns-run.sh")
        self.dir = tempfile.TemporaryDirectory(prefix="far-python-")
        self.socket = os.path.join(self.dir.name, "far.sock")
        self.log_path = os.path.join(self.dir.name, "far-daemon.log")
        with open(self.log_path, "wb") as log:
            self.process = subprocess.Popen(
                [path, "--socket", self.socket, "--log-level", "info",
                 "--max-opens-per-second", "1000", *cost_cache_flags(), *args],
                stdout=log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 60
        while True:
            if self.process.poll() is not None:
                pytest.fail(f"far-daemon exited with {self.process.returncode}:\n{self.log()}")
            try:
                far.Client.status(socket_path=self.socket, connect_timeout=0.3)
                break
            except far.UnavailableError:
                if time.monotonic() > deadline:
                    self.process.kill()
                    pytest.fail(f"far-daemon did not answer within 60 s:\n{self.log()}")

    def log(self):
        with open(self.log_path, errors="replace") as f:
            return f.read()

    def client(self, name="python-test", **options):
        options.setdefault("timeout", 30.0)
        return far.Client(socket_path=self.socket, client_name=name, **options)

    def stop(self):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
                pytest.fail(f"far-daemon did not exit within 10 s of SIGTERM:\n{self.log()}")
        code = self.process.returncode
        log = self.log()
        self.dir.cleanup()
        assert code == 0, f"far-daemon exit code {code}; log:\n{log}"


@pytest.fixture(scope="module")
def daemon():
    d = Daemon()
    yield d
    d.stop()


@pytest.fixture
def own_daemon():
    """A daemon for one test (one that stops or signals it)."""
    d = Daemon()
    yield d
    if d.process.poll() is None:
        os.kill(d.process.pid, signal.SIGCONT)
    d.stop()


@pytest.fixture(scope="session")
def scaling_scene(tmp_path_factory):
    """`far-client make-scene --kind scaling --triangles 1000`: rigid spheres, a deformable
    cloth and a static ground, 4 objects, 1,000 triangles, about a hundred contacts."""
    path = str(tmp_path_factory.mktemp("scene") / "scene.json")
    subprocess.run([os.environ["FAR_CLIENT_PATH"], "make-scene", path, "--kind", "scaling",
                    "--triangles", "1000", "--frames", "2"], check=True, capture_output=True)
    return path
