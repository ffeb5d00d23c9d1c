#!/usr/bin/env bash
# Puts the Kubernetes API's OpenAPI schema, api/openapi-spec/swagger.json of Debian 12's
# kubernetes source package (1.20.5+really1.20.2-1.1+deb12u1: Kubernetes 1.20.2), into DEST
# for validate_manifests.py. The orig tarball (34 MB) comes through apt like LCM's source
# (deploy/fetch-debian-source.sh: the configured sources' deb-src twins, the Sources index's
# SHA-256, pinned here too) into a scratch directory; only swagger.json (5.5 MB) is kept, with its
# own SHA-256 pinned, so a cached copy is checked without the tarball.
#   tests/kubernetes/fetch_openapi_spec.sh [DEST]     # default DEST: <repo>/.deps/kubernetes
# Exit status: 0 DEST/swagger.json is there; 3 no apt archive reachable; 1 anything else.
set -euo pipefail
cd "$(dirname "$0")/../.."

dest=${1:-$PWD/.deps/kubernetes}
version=1.20.5+really1.20.2-1.1+deb12u1
tarball=kubernetes_1.20.5+really1.20.2.orig.tar.gz
tarball_sha256=b83c0780efb182d928dc63d46488a847f161f04e40a94b96bf5247dd671ecdfc
member=kubernetes-1.20.2/api/openapi-spec/swagger.json
swagger_sha256=c7354e6ab4034a89873229a9b7c1fa31fa6242b2e5f5a9b67c3be4fc67cb903c

if [ -f "$dest/swagger.json" ] && echo "$swagger_sha256  $dest/swagger.json" | sha256sum -c --status; then
  echo "fetch-openapi-spec: $dest/swagger.json present"
  exit 0
fi

scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
# 3 (no archive reachable) passes through for the test to skip on; any other failure is 1.
status=0
bash deploy/fetch-debian-source.sh --tag fetch-openapi-spec \
  --why "tests/kubernetes/ validates the manifests against its api/openapi-spec/swagger.json." \
  --rerun "bash tests/kubernetes/fetch_openapi_spec.sh" \
  --else "  - or extract $member from $tarball (sha256 $tarball_sha256)
    to $dest/swagger.json (sha256 $swagger_sha256)." \
  kubernetes "$version" "$tarball" "$tarball_sha256" "$scratch" || status=$?
if [ "$status" -ne 0 ]; then
  [ "$status" -eq 3 ] && exit 3
  exit 1
fi

tar -xzf "$scratch/$tarball" -C "$scratch" "$member"
echo "$swagger_sha256  $scratch/$member" | sha256sum -c --status || {
  echo "fetch-openapi-spec: $member in $tarball does not have the pinned sha256 $swagger_sha256" >&2
  exit 1
}
# Renamed into place, so that a concurrent run never reads half a file.
mkdir -p "$dest"
cp "$scratch/$member" "$dest/.swagger.json.$$"
mv -f "$dest/.swagger.json.$$" "$dest/swagger.json"
echo "fetch-openapi-spec: $dest/swagger.json (Kubernetes 1.20.2, from $tarball)"
