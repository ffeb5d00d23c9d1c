#!/usr/bin/env bash
# Fetches Debian 12's LCM source package (lcm 1.3.1+repack1) through apt into .deps/lcm/, where
# protocol/third_party/lcm/CMakeLists.txt takes the orig tarball from (docs/protocol.md, "Getting
# the source"). deploy/fetch-debian-source.sh does the fetching: through the configured apt
# sources' deb-src twins in a private apt directory, so the repository names no package host.
# Idempotent: nothing is fetched when the tarball is already there with the pinned SHA-256.
#   bash deploy/fetch-lcm-source.sh [DEST]      # default DEST: <repo>/.deps/lcm
set -euo pipefail
cd "$(dirname "$0")/.."

dest=${1:-$PWD/.deps/lcm}
version=1.3.1+repack1-3
tarball=lcm_1.3.1+repack1.orig.tar.gz
# From lcm_1.3.1+repack1-3.dsc; protocol/third_party/lcm/CMakeLists.txt checks it again.
sha256=abf293e54aff3d073cb4f9d4d5a261eab0e5ffea02e13fd601715c11612b85e8

# Any failure is status 1, as before the fetching moved to fetch-debian-source.sh.
bash deploy/fetch-debian-source.sh --tag fetch-lcm-source \
  --why "far builds LCM's C library from it (docs/protocol.md)." \
  --rerun "bash deploy/fetch-lcm-source.sh" \
  --else "  - or copy $tarball (sha256 $sha256) to $dest/,
    or pass -DFAR_LCM_TARBALL=/path/to/$tarball to cmake." \
  lcm "$version" "$tarball" "$sha256" "$dest" || exit 1
