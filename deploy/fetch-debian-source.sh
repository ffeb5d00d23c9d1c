#!/usr/bin/env bash
# Fetches one file of a Debian source package (its orig tarball, say) through apt into DEST and
# checks it against a pinned SHA-256. deploy/fetch-lcm-source.sh (LCM's source, for the build)
# and tests/kubernetes/fetch_openapi_spec.sh (Kubernetes' API schema, for the manifests' test)
# use it. It reaches the archive the way the machine reaches its packages: the same mirrors,
# proxy and keys as the configured apt sources, so it works behind a TLS-inspecting proxy or
# with a local mirror, and the repository names no package host.
#
# apt's own lists are not touched: a deb-src entry is derived from each configured deb entry into
# a private apt directory (sources, lists, cache), `apt-get update` reads only that, and apt's own
# downloader fetches the files with the SHA-256 sums of the signed Sources index.
# Idempotent: nothing is fetched when DEST/FILE is already there with the pinned SHA-256.
#
#   deploy/fetch-debian-source.sh [options] PACKAGE VERSION FILE SHA256 DEST
#     --tag NAME     the prefix of its messages (default: fetch-debian-source)
#     --why TEXT     what the file is for, said when apt cannot find it
#     --rerun CMD    the command to run again once apt reaches an archive
#     --else TEXT    further lines of what to do instead (another way to provide the file)
# Exit status: 0 the file is in DEST with its SHA-256; 1 not found, or a wrong sum; 3 not found
# because apt read no Sources index at all (no archive reachable: offline, or no mirror).
set -euo pipefail

tag=fetch-debian-source
why=""
rerun=""
alternatives=""
while [ $# -gt 0 ]; do
  case "$1" in
    --tag) tag=$2; shift 2 ;;
    --why) why=$2; shift 2 ;;
    --rerun) rerun=$2; shift 2 ;;
    --else) alternatives=$2; shift 2 ;;
    --) shift; break ;;
    -*) echo "$tag: unknown option $1" >&2; exit 1 ;;
    *) break ;;
  esac
done
if [ $# -ne 5 ]; then
  echo "usage: $0 [--tag NAME] [--why TEXT] [--rerun CMD] [--else TEXT] PACKAGE VERSION FILE SHA256 DEST" >&2
  exit 1
fi
package=$1 version=$2 file=$3 sha256=$4 dest=$5

if [ -f "$dest/$file" ] && echo "$sha256  $dest/$file" | sha256sum -c --status; then
  echo "$tag: $dest/$file present"
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
echo "$tag: reading the configured sources' Sources indices (private apt directory)"
# A configured repository without sources (a vendor's binary-only repository) fails its own
# entry only; whether the package was found is what counts, checked below.
apt-get "${apt_opts[@]}" -qq update 2>"$apt_dir/update.err" ||
  echo "$tag: apt-get update reported: $(tr '\n' ' ' <"$apt_dir/update.err")" >&2

# The URIs and SHA-256 sums of the source package's files, from the signed Sources index. Only
# the .dsc and FILE are fetched (some mirrors lack the packaging tarball, which far does not
# use), each by apt's own downloader with its sum checked.
if ! uris=$(apt-get "${apt_opts[@]}" -qq --print-uris source "$package=$version" 2>"$apt_dir/source.err") ||
  ! grep -qF "$file" <<<"$uris"; then
  cat >&2 <<MSG
$tag: apt found no source package $package=$version ($(tr '\n' ' ' <"$apt_dir/source.err")).
  ${why:+$why }Either
  - let apt reach a Debian 12 (bookworm) archive that carries sources (the configured deb entries'
    deb-src twins are used, so a mirror of the binaries usually has them too), then rerun
      ${rerun:-bash $0 $package $version $file $sha256 $dest}
MSG
  [ -z "$alternatives" ] || printf '%s\n' "$alternatives" >&2
  # No Sources index read at all: no archive was reachable, which is not the package's fault.
  if ! compgen -G "$apt_dir/lists/*Sources*" >/dev/null; then exit 3; fi
  exit 1
fi
mkdir -p "$dest"
while read -r uri name _size hash; do
  case "$name" in *.dsc | "$file") ;; *) continue ;; esac
  /usr/lib/apt/apt-helper "${apt_opts[@]}" download-file "${uri//\'/}" "$dest/$name" "$hash" >/dev/null
done < <(grep "^'" <<<"$uris")
echo "$sha256  $dest/$file" | sha256sum -c --status || {
  echo "$tag: $dest/$file does not have the pinned sha256 $sha256" >&2
  exit 1
}
echo "$tag: $(cd "$dest" && ls | tr "\n" " ")in $dest"
