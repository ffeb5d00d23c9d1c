#!/usr/bin/python3
"""Fails when the repository names a host it could fetch from, other than documentation links.

A repository should name no package host: the build takes what it needs through apt, the way
the machine already reaches its packages (its mirrors, proxy and keys; docs/protocol.md,
"Getting the source"), so a URL of a package host, a download mirror or a release tarball in a
script, a CMake file or a doc is either a hidden download or an invitation to one. This test
reads every tracked file (`git ls-files`; outside a git checkout, every file under the source
directory but .git/ and build*/) and checks each URL with a scheme (`name://...`):

- LCM's transport URLs (udpm, mpudpm, memq, tcpq) and file:// name no host to fetch from;
- http(s) links are allowed only to documentation: papers (ALLOWED_HOSTS' "papers"), source
  repositories and their project pages ("source"), the original site of a data set the
  repository ships ("data") and the specification of a file format the repository follows
  ("specifications"); and never to a download (a path ending in an archive or package
  file, a GitHub archive/release/raw path), whatever the host;
- any other scheme (ftp, git, ssh, rsync, ...) fails: documentation links are web pages.

A package is cited by name and version ("the npm package bunny 1.0.1"), never by its registry's
web page: registries, distribution archives and mirrors are not on the list and must not be.
To add a host, add it to the category it belongs to, with what it is.

Skipped: files with a NUL byte in their first 8 KiB (binary, as git decides), the fuzzers'
machine-written inputs (tests/fuzz/corpus/, tests/fuzz/regressions/: made from tracked sources
that are themselves checked), and this file (its lists name the schemes).
Usage: url_allowlist_test.py <source dir>; exit 0 when clean, 1 with one line per finding.
"""
import os
import re
import subprocess
import sys
from urllib.parse import urlsplit

# Schemes that name no host to download from.
LOCAL_SCHEMES = {
    "udpm", "mpudpm", "memq", "tcpq",  # LCM's transports (lcm_create's provider URL)
    "file",  # a local path (the systemd unit's Documentation=)
}
WEB_SCHEMES = {"http", "https"}

# Host -> path prefixes allowed on it ("" for any path), by category.
ALLOWED_HOSTS = {
    "papers": {
        "doi.org": [""],
        "dx.doi.org": [""],
        "arxiv.org": [""],
        "dl.acm.org": ["/doi/"],
        "ieeexplore.ieee.org": ["/document/"],
        "link.springer.com": ["/article/", "/chapter/"],
        "gamma.cs.unc.edu": [""],  # UNC's GAMMA group: the culling papers' project pages
    },
    "source": {
        "github.com": [""],  # <org>/<repo> pages; downloads are refused below
        "gitlab.com": [""],
        "lcm-proj.github.io": [""],  # LCM's documentation (its log file format)
    },
    "data": {
        "graphics.stanford.edu": ["/data/"],  # the Stanford 3D Scanning Repository (bunny)
    },
    "specifications": {
        # The machine-readable copyright format, which deploy/debian/copyright's Format names.
        "www.debian.org": ["/doc/packaging-manuals/copyright-format/"],
    },
}

# Paths that are downloads, on any host: archives and packages, GitHub's generated tarballs,
# release assets and raw files.
DOWNLOAD_PATH = re.compile(
    r"(\.(tar|tgz|tbz2?|txz|gz|bz2|xz|zst|zip|7z|deb|rpm|whl|egg|gem|jar|nupkg|crate|dsc|AppImage)$)"
    r"|(^/[^/]+/[^/]+/(archive|releases/download|raw)/)",
    re.IGNORECASE)

URL = re.compile(r"\b([A-Za-z][A-Za-z0-9+.-]*)://([^\s<>\"'`()\[\]{},;|\\]*)")
SKIPPED_DIRS = ("tests/fuzz/corpus/", "tests/fuzz/regressions/")
THIS_FILE = "tests/repo/url_allowlist_test.py"


def tracked_files(source_dir):
    """Lists the files git tracks, or every file when the source is not a git checkout."""
    try:
        out = subprocess.run(["git", "-C", source_dir, "ls-files", "-z"], check=True,
                             capture_output=True).stdout
        if out:
            return [p for p in out.decode().split("\0") if p]
    except (OSError, subprocess.CalledProcessError):
        pass
    files = []
    for root, dirs, names in os.walk(source_dir):
        rel_root = os.path.relpath(root, source_dir)
        dirs[:] = [d for d in dirs if d != ".git" and not (rel_root == "." and
                                                           (d.startswith("build") or d == ".deps"))]
        files += [os.path.normpath(os.path.join(rel_root, n)) for n in names]
    return files


def judge(scheme, rest):
    """Returns why the URL scheme://rest is not allowed, or None when it is."""
    scheme = scheme.lower()
    if scheme in LOCAL_SCHEMES:
        return None
    if scheme not in WEB_SCHEMES:
        return f"scheme {scheme}:// (only documentation links over http(s) are allowed)"
    parts = urlsplit(f"{scheme}://{rest}")
    host = (parts.hostname or "").lower()
    path = parts.path.rstrip(".")  # a sentence's full stop is not part of the URL
    if DOWNLOAD_PATH.search(path):
        return f"a download ({path})"
    for category, hosts in ALLOWED_HOSTS.items():
        if host in hosts:
            if any(path.startswith(prefix) for prefix in hosts[host]):
                return None
            return f"host {host} is allowed ({category}) only under {hosts[host]}"
    return f"host {host} is not a paper, source repository, data set origin or specification"


def main():
    source_dir = sys.argv[1] if len(sys.argv) > 1 else "."
    findings, checked = [], 0
    for rel in sorted(tracked_files(source_dir)):
        if rel == THIS_FILE or rel.startswith(SKIPPED_DIRS):
            continue
        path = os.path.join(source_dir, rel)
        if not os.path.isfile(path) or os.path.islink(path):
            continue
        with open(path, "rb") as f:
            data = f.read()
        if b"\0" in data[:8192]:
            continue
        checked += 1
        for number, line in enumerate(data.decode("utf-8", "replace").splitlines(), 1):
            for match in URL.finditer(line):
                why = judge(match.group(1), match.group(2))
                if why:
                    findings.append(f"{rel}:{number}: {match.group(0)}: {why}")
    for finding in findings:
        print(finding)
    if findings:
        print(f"url_allowlist_test: {len(findings)} URL(s) outside the allowlist in {checked} "
              f"files (tests/repo/url_allowlist_test.py says what is allowed and why)")
        return 1
    print(f"url_allowlist_test: {checked} files, every URL is a documentation link or local")
    return 0


if __name__ == "__main__":
    sys.exit(main())
