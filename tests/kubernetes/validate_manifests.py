#!/usr/bin/python3
"""Validates Kubernetes manifests offline against the Kubernetes API's OpenAPI schema.

    validate_manifests.py --schema swagger.json PATH...

PATH is a kustomization directory (its kustomization.yaml's `resources`, files or directories,
read recursively) or a YAML file. Every document is checked against the JSON Schema of its kind,
and the result is one line per error, `FILE: KIND/NAME: PATH: message`, then
`N documents, M errors`. Exit status 0 without errors, 1 with, 2 when it cannot run.

Why a program of our own: the tools that do this (kubeconform, kubeval) are not packaged in
Debian 12, and Debian's kubectl 1.20 (kubernetes-client) validates only against a live API
server (`kubectl apply --dry-run=server`, or `--validate` downloading the server's schema);
there is no cluster here. So it does what kubeconform's openapi2jsonschema does, with
Debian's python3-yaml and python3-jsonschema, on the swagger.json of Debian 12's Kubernetes
source (tests/kubernetes/fetch_openapi_spec.sh):

- each definition of the swagger 2.0 `definitions` becomes a JSON Schema definition; a kind's
  schema is its definition (found by `x-kubernetes-group-version-kind`) with `apiVersion` and
  `kind` pinned to it, and `$ref`s resolve into a `definitions` section;
- strict: an object that declares `properties` gets `additionalProperties: false`, so a
  misspelt field is an error (the API server drops unknown fields without a word, and a
  misspelt `runAsUser` would run the container as the image's user);
- `int-or-string` (IntOrString: ports, maxUnavailable) is an integer or a string, and a
  `Quantity` (cpu, memory) a number or a string of Kubernetes' quantity grammar (`512Mi`,
  `100m`, `1e3`), which openapi2jsonschema leaves as any string;
- a null is taken as absent, as the API server takes it (`creationTimestamp: null` from
  `kubectl create --dry-run -o yaml`);
- a ConfigMap's data entry named `*.json` must parse as JSON (the daemon's config).

It does not apply kustomize's transformations (namespace, images): they do not change whether
a document is valid. It refuses a kustomization that uses anything else (patches,
generators), which it could not check as kubectl would render it.
"""
import argparse
import copy
import json
import os
import re
import sys

import jsonschema
import yaml

# Kubernetes' quantity grammar (k8s.io/apimachinery/pkg/api/resource/quantity.go): a signed
# decimal number, then a binary SI suffix, a decimal SI suffix or a decimal exponent.
QUANTITY_PATTERN = r"^[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)(Ki|Mi|Gi|Ti|Pi|Ei|n|u|m|k|M|G|T|P|E|[eE][+-]?[0-9]+)?$"
QUANTITY = "io.k8s.apimachinery.pkg.api.resource.Quantity"
# What kustomization.yaml may hold here: everything else changes what kubectl renders.
KUSTOMIZATION_KEYS = {"apiVersion", "kind", "resources", "namespace", "images"}


class Schemas:
    """The JSON Schemas of every kind in a swagger 2.0 document of the Kubernetes API."""

    def __init__(self, swagger):
        self.definitions = {}
        self.kinds = {}  # (apiVersion, kind) -> definition name
        self.names = {}  # id(converted definition) -> its name, for messages
        for name, definition in swagger["definitions"].items():
            converted = self._convert(copy.deepcopy(definition), name)
            self.definitions[name] = converted
            self.names[id(converted)] = name
            for gvk in definition.get("x-kubernetes-group-version-kind", []):
                api_version = f"{gvk['group']}/{gvk['version']}" if gvk["group"] else gvk["version"]
                self.kinds.setdefault((api_version, gvk["kind"]), name)

    def _convert(self, node, name=None):
        if isinstance(node, list):
            return [self._convert(item) for item in node]
        if not isinstance(node, dict):
            return node
        if node.get("format") == "int-or-string":
            return {"oneOf": [{"type": "integer"}, {"type": "string"}], "x-far-expects": "an integer or a string"}
        if name == QUANTITY:
            return {"oneOf": [{"type": "number"}, {"type": "string", "pattern": QUANTITY_PATTERN}],
                    "x-far-expects": "a quantity (a number, or a string such as 512Mi, 100m, 2)"}
        converted = {key: self._convert(value) for key, value in node.items()}
        if "properties" in converted and "additionalProperties" not in converted:
            converted["additionalProperties"] = False
        return converted

    def validator(self, api_version, kind):
        name = self.kinds.get((api_version, kind))
        if name is None:
            return None, None
        schema = {
            "allOf": [
                {"$ref": "#/definitions/" + name},
                {"properties": {"apiVersion": {"enum": [api_version]}, "kind": {"enum": [kind]}}},
            ],
            "definitions": self.definitions,
        }
        return jsonschema.Draft7Validator(schema), name


def without_nulls(value):
    if isinstance(value, dict):
        return {k: without_nulls(v) for k, v in value.items() if v is not None}
    if isinstance(value, list):
        return [without_nulls(v) for v in value]
    return value


def path_text(path):
    """spec.containers[0].resources, with keys such as nvidia.com/gpu in brackets and quotes."""
    text = ""
    for part in path:
        if isinstance(part, int):
            text += f"[{part}]"
        elif re.fullmatch(r"[A-Za-z0-9_-]+", str(part)):
            text += f".{part}" if text else str(part)
        else:
            text += f'["{part}"]'
    return text or "(document)"


def describe(error, schemas):
    """One line per problem of a jsonschema error: the path to it and what is wrong."""
    path = list(error.absolute_path)
    if error.validator == "additionalProperties" and isinstance(error.instance, dict):
        known = error.schema.get("properties", {})
        owner = schemas.names.get(id(error.schema), "its object")
        return [(path + [key], f"unknown field (not in {owner})")
                for key in sorted(error.instance) if key not in known]
    if error.validator == "oneOf" and "x-far-expects" in error.schema:
        return [(path, f"{error.instance!r} is not {error.schema['x-far-expects']}")]
    return [(path, error.message)]


def kustomization_files(directory, errors):
    """The YAML files a kustomization directory's resources name, in order."""
    path = os.path.join(directory, "kustomization.yaml")
    with open(path) as f:
        kustomization = yaml.safe_load(f) or {}
    unsupported = sorted(set(kustomization) - KUSTOMIZATION_KEYS)
    if unsupported:
        errors.append(f"{path}: {', '.join(unsupported)}: not checked by this validator (it reads "
                      f"{', '.join(sorted(KUSTOMIZATION_KEYS))} only); render with kubectl kustomize")
    files = []
    for resource in kustomization.get("resources", []):
        resource_path = os.path.normpath(os.path.join(directory, resource))
        if os.path.isdir(resource_path):
            files += kustomization_files(resource_path, errors)
        elif os.path.isfile(resource_path):
            files.append(resource_path)
        else:
            errors.append(f"{path}: resource {resource} does not exist")
    return files


def check_document(document, schemas):
    """The errors of one document, as (path, message)."""
    if not isinstance(document, dict):
        return [([], "a document must be a mapping")]
    api_version, kind = document.get("apiVersion"), document.get("kind")
    validator, _ = schemas.validator(api_version, kind)
    if validator is None:
        return [([], f"no schema for apiVersion {api_version!r}, kind {kind!r} in this API version")]
    problems = []
    for error in validator.iter_errors(document):
        problems += describe(error, schemas)
    if kind == "ConfigMap":
        for key, value in (document.get("data") or {}).items():
            if key.endswith(".json") and isinstance(value, str):
                try:
                    json.loads(value)
                except json.JSONDecodeError as e:
                    problems.append((["data", key], f"not JSON: {e}"))
    return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--schema", required=True, help="the API's swagger.json (OpenAPI 2.0)")
    parser.add_argument("paths", nargs="+", help="kustomization directories or YAML files")
    args = parser.parse_args()
    try:
        with open(args.schema) as f:
            schemas = Schemas(json.load(f))
    except (OSError, ValueError, KeyError) as e:
        print(f"validate_manifests: cannot read the schema {args.schema}: {e}", file=sys.stderr)
        return 2

    errors = []
    files = []
    for path in args.paths:
        if os.path.isdir(path):
            files += kustomization_files(path, errors)
        else:
            files.append(path)
    documents = 0
    for file in files:
        try:
            with open(file) as f:
                loaded = [d for d in yaml.safe_load_all(f) if d is not None]
        except (OSError, yaml.YAMLError) as e:
            errors.append(f"{file}: cannot read: {e}")
            continue
        for document in loaded:
            documents += 1
            document = without_nulls(document)
            name = (document.get("metadata") or {}).get("name", "?") if isinstance(document, dict) else "?"
            where = f"{file}: {document.get('kind', '?') if isinstance(document, dict) else '?'}/{name}"
            problems = check_document(document, schemas)
            for path, message in sorted(problems, key=lambda p: (path_text(p[0]), p[1])):
                errors.append(f"{where}: {path_text(path)}: {message}")
    for error in errors:
        print(error)
    print(f"{documents} documents, {len(errors)} errors")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
