#!/usr/bin/python3
"""far-daemon's Prometheus metrics (docs/daemon.md, "Metrics"), as a cluster collects them.

  metrics_test.py values FAR_DAEMON FAR_CLIENT
    A daemon with --metrics-file (rewritten every second) and --metrics-port serves clients'
    steps (by auto, and by far) and a few malformed connections; once it is idle, the file and
    the port's body parse with prometheus_client's parser, every family has HELP and TYPE, the
    latency quantiles are ordered, and the values equal `far-client status --json` taken at the
    same quiet moment (resident memory within 64 MiB: it moves with every status asked).
    Another process reads the file in a tight loop while the daemon rewrites it: every read is
    a whole file. After SIGTERM the last file stays, saying far_up 0 and no session. A file in a
    directory that does not exist is refused at start (exit status 2).
  metrics_test.py loopback FAR_DAEMON FAR_CLIENT
    The port listens on 127.0.0.1 only (ss; 127.0.0.2 and ::1 are refused), and a second
    daemon asking for the same port exits 1 naming it.

Run inside deploy/netns-run.sh (a private loopback: LCM multicast, and ports of its own).
Exit 0 when every check passes, 1 with the failed check on stderr.
"""
import ctypes
import http.client
import json
import math
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time

from prometheus_client.parser import text_string_to_metric_families

DAEMON_NAME = "metrics"
PORT = 9464
# Every family the daemon writes (the parser names a counter's family without "_total").
FAR_FAMILIES = {
    "far_up", "far_info", "far_uptime_seconds", "far_sessions_open", "far_sessions_max",
    "far_sessions_max_per_user", "far_scene_objects", "far_scene_triangles", "far_steps",
    "far_step_latency_seconds", "far_errors", "far_rejected_messages", "far_gpu_info",
    "far_memory_rss_bytes", "far_segment_bytes", "far_opens_refused", "far_steps_by_method",
    "far_gpu_batched_steps", "far_gpu_batches",
}
# What the daemon's scheduler calls its GPU (--serves-gpus), added to what it detects.
SERVES_GPUS = ["3", "GPU-metrics-test"]
# The methods that run on the GPU (far::NeedsGl); the others run on the CPU.
GPU_METHODS = {"far", "far-exact-offset", "cullide", "gpu"}


class Failure(Exception):
    pass


def check(condition, what):
    if not condition:
        raise Failure(what)


def close(a, b):
    return math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-15)


def die_with_parent():
    # A daemon whose test was killed (ctest's timeout) ends with it: PR_SET_PDEATHSIG.
    ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)


class Daemon:
    """One far-daemon with its own socket directory; stopped by stop() or on exit."""

    def __init__(self, daemon, client, work, name, flags):
        self.client = client
        self.name = name
        self.env = dict(os.environ, FAR_SOCKET_DIR=os.path.join(work, "run"))
        os.makedirs(self.env["FAR_SOCKET_DIR"], mode=0o700, exist_ok=True)
        self.log_path = os.path.join(work, name + ".log")
        with open(self.log_path, "w") as log:
            # The tree's shared GPU cost cache, when ctest names it (docs/testing.md).
            cache = os.environ.get("FAR_TEST_GPU_COST_CACHE")
            cache_flags = ["--gpu-cost-cache", cache] if cache else []
            self.process = subprocess.Popen([daemon, "--name", name, *cache_flags, *flags],
                                            env=self.env,
                                            stdout=log, stderr=subprocess.STDOUT,
                                            preexec_fn=die_with_parent)
        ping = self.run_client("--connect-timeout", "60s", "ping", check_rc=False)
        if ping.returncode != 0:
            raise Failure(f"daemon {name} did not answer: {ping.stderr}\n{self.log()}")

    def log(self):
        with open(self.log_path) as log:
            return log.read()

    def run_client(self, *args, check_rc=True):
        done = subprocess.run([self.client, "--daemon", self.name, *args], env=self.env,
                              capture_output=True, text=True, timeout=120)
        if check_rc and done.returncode != 0:
            raise Failure(f"far-client {' '.join(args)}: exit {done.returncode}: {done.stderr}")
        return done

    def status(self):
        return json.loads(self.run_client("status", "--json").stdout)

    def stop(self):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        return self.process.returncode


def families_of(text, where):
    """Parses Prometheus text: {family name: family}. Every family must say HELP and TYPE."""
    families = {}
    try:
        for family in text_string_to_metric_families(text):
            families[family.name] = family
    except Exception as e:  # the parser raises ValueError and others on malformed text
        raise Failure(f"{where}: does not parse: {e!r}\n{text}")
    for name, family in families.items():
        check(family.documentation, f"{where}: {name} has no HELP")
        check(family.type != "unknown", f"{where}: {name} has no TYPE")
    return families


def read_file(path):
    with open(path) as f:
        return f.read()


def scrape(port, host="127.0.0.1"):
    connection = http.client.HTTPConnection(host, port, timeout=10)
    try:
        connection.request("GET", "/metrics")
        response = connection.getresponse()
        body = response.read().decode()
        check(response.status == 200, f"GET /metrics: {response.status}")
        check(response.getheader("Content-Type", "").startswith("text/plain"),
              f"Content-Type {response.getheader('Content-Type')}")
        return body
    finally:
        connection.close()


def sample(families, family, suffix="", **labels):
    """The one sample of `family` named family+suffix whose labels include `labels`."""
    found = [s for s in families[family].samples
             if s.name == family + suffix and all(s.labels.get(k) == v for k, v in labels.items())]
    check(len(found) == 1, f"{family}{suffix}{labels}: {len(found)} samples, not 1")
    return found[0].value


def check_against_status(families, status, where):
    """The far_* families against `far-client status --json` of the same quiet moment."""
    check(FAR_FAMILIES <= families.keys(),
          f"{where}: missing families {sorted(FAR_FAMILIES - families.keys())}")
    for name in FAR_FAMILIES:
        for s in families[name].samples:
            check(s.labels.get("daemon") == DAEMON_NAME, f"{where}: {s} has no daemon label")
    check(sample(families, "far_up") == 1, f"{where}: far_up is not 1")
    info = families["far_info"].samples[0].labels
    for label, key in (("version", "daemon_version"), ("gl_renderer", "gl_renderer"),
                       ("gl_device", "gl_device"), ("pid", "daemon_pid")):
        check(info[label] == str(status[key]), f"{where}: far_info {label} {info[label]!r}")
    gpus = sorted(s.labels["gpu"] for s in families["far_gpu_info"].samples)
    check(gpus == sorted(status["gpu_names"]) and set(SERVES_GPUS) <= set(gpus),
          f"{where}: far_gpu_info {gpus} != {status['gpu_names']}")
    # Resident memory moves a little with every status asked; the rest may not move.
    rss = sample(families, "far_memory_rss_bytes")
    check(abs(rss - status["memory_rss_bytes"]) < 64 << 20,
          f"{where}: far_memory_rss_bytes {rss} far from {status['memory_rss_bytes']}")
    uptime = sample(families, "far_uptime_seconds")
    check(0 < uptime <= status["uptime_ms"] / 1000, f"{where}: far_uptime_seconds {uptime}")
    for family, value in (("far_sessions_open", status["sessions_open"]),
                          ("far_segment_bytes", status["segment_bytes"]),
                          ("far_sessions_max", status["max_sessions"]),
                          ("far_sessions_max_per_user", status["max_sessions_per_user"]),
                          ("far_scene_objects", sum(s["objects"] for s in status["sessions"])),
                          ("far_scene_triangles",
                           sum(s["triangles"] for s in status["sessions"]))):
        check(sample(families, family) == value, f"{where}: {family} != {value}")
    check(sample(families, "far_steps", "_total") == status["steps_total"],
          f"{where}: far_steps_total != {status['steps_total']}")
    check(sample(families, "far_rejected_messages", "_total") ==
          status["rejected_messages_total"], f"{where}: far_rejected_messages_total")
    check(sample(families, "far_opens_refused", "_total") == status["opens_refused_total"],
          f"{where}: far_opens_refused_total")
    by_method = {s.labels["method"]: s.value for s in families["far_steps_by_method"].samples}
    check(by_method == status["steps_by_method"],
          f"{where}: far_steps_by_method_total {by_method} != {status['steps_by_method']}")
    for s in families["far_steps_by_method"].samples:
        device = "gpu" if s.labels["method"] in GPU_METHODS else "cpu"
        check(s.labels["device"] == device, f"{where}: {s.labels} is not on the {device}")
    errors = {s.labels["kind"]: s.value for s in families["far_errors"].samples}
    check(errors == status["errors_by_kind"],
          f"{where}: far_errors_total {errors} != {status['errors_by_kind']}")
    # The summary: the status' quantiles in seconds, ordered; count and sum since start.
    latency = status["latency_ms"]
    quantiles = []
    for q, key in (("0.5", "p50"), ("0.9", "p90"), ("0.99", "p99"), ("1", "max")):
        value = sample(families, "far_step_latency_seconds", quantile=q)
        check(close(value, latency[key] / 1000),
              f"{where}: quantile {q} {value} != {latency[key]} ms")
        quantiles.append(value)
    check(quantiles == sorted(quantiles), f"{where}: quantiles not ordered: {quantiles}")
    count = sample(families, "far_step_latency_seconds", "_count")
    total = sample(families, "far_step_latency_seconds", "_sum")
    check(count == latency["samples"], f"{where}: _count {count} != {latency['samples']}")
    # Every step is still in the 8192-step window: the mean lies between its extremes.
    check(count > 0 and 0 < total <= count * quantiles[-1] * (1 + 1e-12),
          f"{where}: _sum {total} for {count} steps of at most {quantiles[-1]} s")


def read_loop(path, seconds):
    """Reads `path` as fast as it can for `seconds`: prints reads, distinct contents, failures."""
    reads, contents, failures = 0, set(), []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        text = read_file(path)
        reads += 1
        contents.add(text)
        try:
            names = set(families_of(text, "read").keys())
            if names != FAR_FAMILIES or not text.endswith("\n"):
                failures.append(f"partial: families {sorted(names)}")
        except Failure as e:
            failures.append(str(e))
    print(json.dumps({"reads": reads, "distinct": len(contents), "failures": failures[:3],
                      "failed": len(failures)}))


def quiet_status(daemon, file_path, steps):
    """Waits until the daemon is idle with `steps` steps done and the file written since."""
    deadline = time.monotonic() + 60
    while True:
        status = daemon.status()
        # (a closed session's segment is given back when its worker is reaped, a little after)
        if (status["sessions_open"] == 0 and status["segment_bytes"] == 0 and
                status["steps_total"] == steps and
                status["errors_by_kind"].get("parse_error") == 3):
            break
        check(time.monotonic() < deadline, f"the daemon did not settle: {status}")
        time.sleep(0.2)
    # A rewrite after that moment: the file's uptime passes the status'.
    while sample(families_of(read_file(file_path), "file"), "far_uptime_seconds") <= \
            status["uptime_ms"] / 1000:
        check(time.monotonic() < deadline, "the file was not rewritten within 60 s")
        time.sleep(0.1)
    return status


def without_uptime(status):
    return {k: v for k, v in status.items() if k not in ("uptime_ms", "memory_rss_bytes")}


def test_values(daemon_path, client_path, work):
    file_path = os.path.join(work, "textfile", "far.prom")
    os.makedirs(os.path.dirname(file_path))
    # A file in a directory that does not exist: a configuration error, exit status 2.
    refused = subprocess.run([daemon_path, "--name", DAEMON_NAME, "--metrics-file",
                              os.path.join(work, "missing", "far.prom")],
                             capture_output=True, text=True, timeout=60)
    check(refused.returncode == 2 and "does not exist" in refused.stderr,
          f"missing directory: exit {refused.returncode}: {refused.stderr}")

    t0 = time.monotonic()
    daemon = Daemon(daemon_path, client_path, work, DAEMON_NAME,
                    ["--metrics-file", file_path, "--metrics-port", str(PORT),
                     "--metrics-interval-s", "1", "--serves-gpus", ",".join(SERVES_GPUS)])
    try:
        # Written before the daemon answered.
        first = families_of(read_file(file_path), "first file")
        check(sample(first, "far_up") == 1, "first file: far_up is not 1")
        # Steps of 3 clients (auto's choice, on the CPU here) and of one client stepping far
        # (on the GPU), and 3 connections that send what is neither open nor status.
        daemon.run_client("load", "--clients", "3", "--steps", "20")
        daemon.run_client("load", "--clients", "1", "--steps", "10", "--method", "far")
        for _ in range(3):
            with socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET) as s:
                s.connect(os.path.join(daemon.env["FAR_SOCKET_DIR"], DAEMON_NAME + ".sock"))
                s.send(b"not a far message")
        before = quiet_status(daemon, file_path, 70)
        file_text = read_file(file_path)
        port_text = scrape(PORT)
        after = daemon.status()
        check(without_uptime(before) == without_uptime(after),
              f"the daemon was not quiet:\n{before}\n{after}")
        check_against_status(families_of(file_text, "file"), after, "file")
        port = families_of(port_text, "port")
        check_against_status(port, after, "port")
        print(f"file and port match the status: {after['steps_total']} steps, errors "
              f"{after['errors_by_kind']}, by method {after['steps_by_method']}, "
              f"GPU names {after['gpu_names']}, p50 {after['latency_ms']['p50']:.3f} ms "
              f"({time.monotonic() - t0:.1f} s)")

        # Another process reads the file while the daemon rewrites it every second.
        reader = subprocess.run([sys.executable, __file__, "read-loop", file_path, "4"],
                                capture_output=True, text=True, timeout=60)
        check(reader.returncode == 0, f"reader: {reader.stderr}")
        seen = json.loads(reader.stdout)
        check(seen["failed"] == 0, f"reads that were not a whole file: {seen}")
        check(seen["distinct"] >= 3 and seen["reads"] >= 100,
              f"the reader did not see the file rewritten: {seen}")
        print(f"{seen['reads']} reads of {seen['distinct']} versions of the file, all whole")

        steps = daemon.status()["steps_total"]
        check(daemon.stop() == 0, f"daemon exit {daemon.process.returncode}\n{daemon.log()}")
        # The last file: a clean stop, its final counters.
        last = families_of(read_file(file_path), "last file")
        check(sample(last, "far_up") == 0, "last file: far_up is not 0")
        check(sample(last, "far_sessions_open") == 0, "last file: sessions open")
        check(sample(last, "far_steps", "_total") == steps, "last file: far_steps_total")
        leftovers = sorted(set(os.listdir(os.path.dirname(file_path))) - {"far.prom"})
        check(not leftovers, f"temporary files left: {leftovers}")
        print(f"the last file says far_up 0 ({time.monotonic() - t0:.1f} s)")
    finally:
        daemon.stop()


def listening(port):
    """The local addresses listening on TCP `port`, as ss prints them."""
    out = subprocess.run(["ss", "-ltnH"], capture_output=True, text=True, check=True).stdout
    return [line.split()[3] for line in out.splitlines() if line.split()[3].endswith(f":{port}")]


def refused(family, host, port):
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.settimeout(5)
        try:
            s.connect((host, port))
        except OSError:
            return True
    return False


def test_loopback(daemon_path, client_path, work):
    daemon = Daemon(daemon_path, client_path, work, DAEMON_NAME, ["--metrics-port", str(PORT)])
    try:
        addresses = listening(PORT)
        check(addresses == [f"127.0.0.1:{PORT}"], f"listening on {addresses}")
        # Another loopback address and IPv6's: nothing listens there (a wildcard would answer).
        check(refused(socket.AF_INET, "127.0.0.2", PORT), "127.0.0.2 answered")
        check(refused(socket.AF_INET6, "::1", PORT), "::1 answered")
        check(sample(families_of(scrape(PORT), "port"), "far_up") == 1, "far_up is not 1")
        # The port taken: a second daemon says so and exits 1.
        second = subprocess.run([daemon_path, "--name", "second", "--metrics-port", str(PORT)],
                                env=daemon.env, capture_output=True, text=True, timeout=60)
        check(second.returncode == 1 and f"127.0.0.1:{PORT}" in second.stderr,
              f"second daemon on the port: exit {second.returncode}: {second.stderr}")
        print(f"listening on {addresses} only; a second daemon: {second.stderr.strip()}")
        check(daemon.stop() == 0, f"daemon exit {daemon.process.returncode}")
        check(listening(PORT) == [], "the port stayed open after the daemon stopped")
    finally:
        daemon.stop()


def main():
    if sys.argv[1] == "read-loop":
        return read_loop(sys.argv[2], float(sys.argv[3]))
    mode, daemon_path, client_path = sys.argv[1:4]
    test = {"values": test_values, "loopback": test_loopback}[mode]
    with tempfile.TemporaryDirectory(prefix="far-metrics-test-") as work:
        try:
            test(daemon_path, client_path, work)
        except Failure as e:
            print(f"metrics_test {mode}: {e}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
