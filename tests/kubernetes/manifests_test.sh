#!/usr/bin/env bash
# The Kubernetes manifests (deploy/kubernetes/) checked offline against the Kubernetes API's
# schema: validate_manifests.py on the swagger.json of Debian 12's kubernetes source package
# (fetch_openapi_spec.sh, cached in .deps/kubernetes/). No cluster is needed.
#   1. deploy/kubernetes and deploy/kubernetes/example: 0 errors;
#   2. tests/kubernetes/bad/ (a misspelt field, a wrong type, a malformed quantity, beside valid
#      int-or-string and quantity forms): exactly the errors of bad/expected.txt, so the
#      validator is seen to catch them;
#   3. the image tag of the manifests and the .deb of the Dockerfile are this version's;
#   4. where kubectl is on PATH: `kubectl kustomize` renders both, and its rendering validates
#      with 0 errors too (skipped, saying so, without kubectl: Debian's kubernetes-client is
#      not required).
# Exit 77 (skipped) only when apt reaches no archive for the schema's source package.
#   tests/kubernetes/manifests_test.sh <source dir> <version>
set -euo pipefail
source_dir=$1
version=$2
cd "$source_dir"
validate=(/usr/bin/python3 tests/kubernetes/validate_manifests.py --schema .deps/kubernetes/swagger.json)
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f s", b - a }'; }

t0=$(now)
status=0
bash tests/kubernetes/fetch_openapi_spec.sh || status=$?
if [ "$status" -eq 3 ]; then
  echo "SKIP: apt reaches no archive with Debian 12's sources (offline?), so there is no Kubernetes API schema to validate against"
  exit 77
fi
[ "$status" -eq 0 ] || fail "could not fetch the Kubernetes API schema (above)"
echo "schema: $(since "$t0")"

t0=$(now)
"${validate[@]}" deploy/kubernetes deploy/kubernetes/example >"$scratch/good.txt" ||
  { cat "$scratch/good.txt"; fail "deploy/kubernetes does not validate"; }
cat "$scratch/good.txt"
grep -qx "[1-9][0-9]* documents, 0 errors" "$scratch/good.txt" || fail "no documents validated"
echo "manifests: $(since "$t0")"

t0=$(now)
bad_status=0
"${validate[@]}" tests/kubernetes/bad >"$scratch/bad.txt" || bad_status=$?
[ "$bad_status" -eq 1 ] || { cat "$scratch/bad.txt"; fail "the bad manifest: exit $bad_status, not 1"; }
diff -u tests/kubernetes/bad/expected.txt "$scratch/bad.txt" ||
  fail "the bad manifest's errors are not those of tests/kubernetes/bad/expected.txt"
echo "bad manifest: its $(tail -1 "$scratch/bad.txt"), as expected ($(since "$t0"))"

# Every far image the manifests run, and the package the Dockerfile installs, are this version.
images=$(grep -rhoE "image: *[^ ]+|newTag: *[^ ]+" deploy/kubernetes --include='*.yaml' | sort -u)
for image in $images; do
  case "$image" in image: | newTag:) continue ;; far:"$version" | "$version") ;;
    *) fail "deploy/kubernetes names $image, not far:$version" ;; esac
done
grep -qx "ARG FAR_DEB=far_${version}_amd64.deb" deploy/kubernetes/Dockerfile ||
  fail "deploy/kubernetes/Dockerfile does not install far_${version}_amd64.deb"
echo "image: far:$version throughout"

if ! command -v kubectl >/dev/null; then
  echo "SKIPPED PART: kubectl is not on PATH, so kubectl kustomize was not run (Debian's kubernetes-client has it)"
  exit 0
fi
t0=$(now)
for dir in deploy/kubernetes deploy/kubernetes/example; do
  out="$scratch/$(basename "$dir").yaml"
  kubectl kustomize "$dir" >"$out" 2>"$scratch/kustomize.err" ||
    { cat "$scratch/kustomize.err"; fail "kubectl kustomize $dir"; }
  "${validate[@]}" "$out" >"$scratch/rendered.txt" ||
    { cat "$scratch/rendered.txt"; fail "kubectl kustomize $dir renders manifests that do not validate"; }
  echo "kubectl kustomize $dir: $(tail -1 "$scratch/rendered.txt")"
done
echo "kustomize ($(kubectl version --client 2>/dev/null | head -1)): $(since "$t0")"
