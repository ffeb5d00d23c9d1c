#!/usr/bin/env bash
# Fetches Debian 12's LCM source package (lcm 1.3.1+repack1) through apt into .deps/lcm/, where
# protocol/third_party/lcm/CMakeLists.txt takes the orig tarball from (docs/protocol.md, "Getting
# the source"). It reaches the archive the way the machine reaches its packages: the same
# mirrors, proxy and keys as the configured apt sources, so it works behind a TLS-inspecting
# proxy or with a local mirror, and the repository names no package host.
#
# apt's own lists are not touched: a deb-src entry is derived from each configured deb entry into
# a private apt directory (sources, lists, cache), `apt-get update` reads only that, and apt's own
# downloader fetches the files with the SHA-256 sums of the signed Sources index.
# Idempotent: nothing is fetched when the tarball is already there with the pinned SHA-256.
#   bash deploy/fetch-lcm-source.sh [DEST]      # default DEST: <repo>/.deps/lcm
set -euo pipefail
cd "$(dirname "$0")/.."

dest=${1:-$PWD/.deps/lcm}
version=1.3.1+repack1-3
tarball=lcm_1.3.1+repack1.orig.tar.gz
# From lcm_1.3.1+repack1-3.dsc; protocol/third_party/lcm/CMakeLists.txt checks it again.
sha256=abf293e54aff3d073cb4f9d4d5a261eab0e5ffea02e13fd601715c11612b85e8

if [ -f "$dest/$tarball" ] && echo "$sha256  $dest/$tarball" | sha256sum -c --status; then
  echo "fetch-lcm-source: $dest/$tarball present"
  exit 0
fi

# The private apt directory: deb-src twins of the configured deb entries, in both formats.
apt_dir=$(mktemp -d)
trap 'rm -rf "$apt_dir"' EXIT
mkdir -p "$apt_dir/sources.list.d" "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial"
if [ -f /etc/apt/sources.list ]; then
  sed -nE 's/^[[:space:]]*deb([[:space:]])/deb-src\1/p' /etc/apt/sources.list \
    >"$apt_dir/sources.list"
fi
: >>"$apt_dir/sources.list"
for f in /etc/apt/sources.list.d/*.list; do
  [ -f "$f" ] || continue
  sed -nE 's/^[[:space:]]*deb([[:space:]])/deb-src\1/p' "$f" >"$apt_dir/sources.list.d/$(basename "$f")"
done
for f in /etc/apt/sources.list.d/*.sources; do
  [ -f "$f" ] || continue
  # deb822: a stanza of Types "deb" becomes "deb-src"; stanzas that already list deb-src stay.
  sed -E 's/^Types:[[:space:]]*deb[[:space:]]*$/Types: deb-src/I' "$f" \
    >"$apt_dir/sources.list.d/$(basename "$f")"
done

apt_opts=(
  -o "Dir::Etc::SourceList=$apt_dir/sources.list"
  -o "Dir::Etc::SourceParts=$apt_dir/sources.list.d"
  -o "Dir::State::Lists=$apt_dir/lists"
  -o "Dir::Cache=$apt_dir/cache"
  -o "Dir::Cache::pkgcache=" -o "Dir::Cache::srcpkgcache="
  # As root apt downloads as the _apt user, which cannot write a private directory of root's.
  -o "APT::Sandbox::User=$(id -un)"
  -o "Debug::NoLocking=1"
)
echo "fetch-lcm-source: reading the configured sources' Sources indices (private apt directory)"
# A configured repository without sources (a vendor's binary-only repository) fails its own
# entry only; whether lcm was found is what counts, checked below.
apt-get "${apt_opts[@]}" -qq update 2>"$apt_dir/update.err" ||
  echo "fetch-lcm-source: apt-get update reported: $(tr '\n' ' ' <"$apt_dir/update.err")" >&2

# The URIs and SHA-256 sums of the source package's files, from the signed Sources index. Only
# the .dsc and the orig tarball are fetched (some mirrors lack the packaging tarball, which far
# does not use), each by apt's own downloader with its sum checked.
if ! uris=$(apt-get "${apt_opts[@]}" -qq --print-uris source "lcm=$version" 2>"$apt_dir/source.err") ||
  ! grep -q "$tarball" <<<"$uris"; then
  cat >&2 <<MSG
fetch-lcm-source: apt found no source package lcm=$version ($(tr '\n' ' ' <"$apt_dir/source.err")).
  far builds LCM's C library from it (docs/protocol.md). Either
  - let apt reach a Debian 12 (bookworm) archive that carries sources (the configured deb entries'
    deb-src twins are used, so a mirror of the binaries usually has them too), then rerun
      bash deploy/fetch-lcm-source.sh
  - or copy $tarball (sha256 $sha256) to $dest/,
    or pass -DFAR_LCM_TARBALL=/path/to/$tarball to cmake.
MSG
  exit 1
fi
mkdir -p "$dest"
while read -r uri file _size hash; do
  case "$file" in *.dsc | "$tarball") ;; *) continue ;; esac
  /usr/lib/apt/apt-helper "${apt_opts[@]}" download-file "${uri//\'/}" "$dest/$file" "$hash" >/dev/null
done < <(grep "^'" <<<"$uris")
echo "$sha256  $dest/$tarball" | sha256sum -c --status || {
  echo "fetch-lcm-source: $dest/$tarball does not have the pinned sha256 $sha256" >&2
  exit 1
}
echo "fetch-lcm-source: $(cd "$dest" && ls | tr "\n" " ")in $dest"
