#!/usr/bin/env bash
# ctest entry for deploy/k8s (no cluster needed):
#   check   deploy/k8s/check_manifests.py on the sources, then on copies broken on purpose (each
#           must fail naming what broke). Needs Debian's python3-yaml (deploy/setup.sh installs it).
#   render  `kubectl kustomize` of the default (TLS) and of the plain-text variant with throwaway
#           secrets, each rendering checked by check_manifests.py --rendered. kubectl is not a
#           Debian package: skipped (exit 77) where it is absent.
set -euo pipefail
REPO="$(cd "$(dirname "$0")/../.." && pwd)"
CHECK="$REPO/deploy/k8s/check_manifests.py"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

if ! /usr/bin/python3 -c 'import yaml' 2>/dev/null; then
  echo "k8s tests: skipped, /usr/bin/python3 has no yaml module (apt-get install python3-yaml)"
  exit 77
fi

# Copies deploy/k8s to $WORK/$1, applies the sed expression $3 to file $2, expects the check to
# fail with a message holding $4.
expect_failure() {
  local name="$1" file="$2" expression="$3" message="$4" output
  cp -r "$REPO/deploy/k8s" "$WORK/$name"
  sed -i "$expression" "$WORK/$name/$file"
  if output="$(/usr/bin/python3 "$CHECK" "$WORK/$name" 2>&1)"; then
    echo "FAIL: $name: the check passed a broken copy ($file: $expression)"; exit 1
  fi
  grep -qF -- "$message" <<<"$output" || { echo "FAIL: $name: expected '$message' in:"; echo "$output"; exit 1; }
  echo "ok: $name is caught ($message)"
}

check() {
  /usr/bin/python3 "$CHECK" "$REPO/deploy/k8s"
  expect_failure selector server-service.yaml 's/^    app.kubernetes.io\/name: modskill-server$/    app.kubernetes.io\/name: other/' \
    "selector app.kubernetes.io/name=other matches no pod label"
  expect_failure flag learner-job.yaml 's/--preset=small/--preset_name=small/' "modskill-learner has no --preset_name"
  expect_failure port learner-job.yaml 's/svc.cluster.local:50051/svc.cluster.local:50052/' "--servers port 50052 is not a Service port"
  expect_failure secret server-deployment.yaml 's/secretName: modskill-token/secretName: modskill-tokens/' \
    "mounts Secret modskill-tokens, which the kustomization does not generate"
  expect_failure env learner-job.yaml 's/key: envs_per_server/key: envs/' "ConfigMap modskill-sizes has no key envs"
  expect_failure image server-deployment.yaml 's/image: modskill /image: debian:12 /' "image debian:12, expected modskill"
  expect_failure probe tls/server-tls.yaml 's/--tls_server_name/--server_name/' "modskill-client has no --server_name"
  expect_failure listed kustomization.yaml '/- learner-job.yaml/d' "learner-job.yaml: not listed in the kustomization"
  # The data-parallel component (checked whether or not it is enabled), and enabled.
  expect_failure ranks data-parallel/learner-ranks-job.yaml 's/completions: 2/completions: 3/' \
    "completions 3 differs from --world_size=2"
  expect_failure subdomain data-parallel/learner-ranks-job.yaml 's/subdomain: modskill-learner-ranks/subdomain: other/' \
    "the Job's subdomain other is not the Service modskill-learner-ranks"
  expect_failure rendezvous data-parallel/kustomization.yaml 's/modskill-learner-0\./modskill-learner-1./' \
    "--rendezvous=modskill-learner-1."
  expect_failure rank_flag data-parallel/kustomization.yaml 's/--rank=/--rank_index=/' '--rank_index=$(MODSKILL_RANK): modskill-learner has no such flag'
  cp -r "$REPO/deploy/k8s" "$WORK/ranks_enabled"
  sed -i 's/^  - tls$/  - tls\n  - data-parallel/' "$WORK/ranks_enabled/kustomization.yaml"
  grep -q -- "- data-parallel" "$WORK/ranks_enabled/kustomization.yaml" || { echo "FAIL: could not enable data-parallel"; exit 1; }
  /usr/bin/python3 "$CHECK" "$WORK/ranks_enabled"
}

# Throwaway secrets where the kustomization expects them (deploy/k8s/secrets/, never committed).
make_secrets() {
  local dir="$1/secrets"
  mkdir -p "$dir"
  head -c 32 /dev/urandom | base64 > "$dir/token"
  if command -v openssl > /dev/null; then
    openssl req -x509 -newkey rsa:2048 -nodes -days 1 -keyout "$dir/tls.key" -out "$dir/tls.crt" \
      -subj "/CN=modskill-server.modskill.svc.cluster.local" 2> /dev/null
  else
    echo "not a certificate" > "$dir/tls.crt"; echo "not a key" > "$dir/tls.key"
  fi
  cp "$dir/tls.crt" "$dir/ca.crt"
}

render() {
  if ! command -v kubectl > /dev/null; then
    echo "k8s render test: skipped, no kubectl (not a Debian package; see deploy/k8s/README.md)"
    exit 77
  fi
  cp -r "$REPO/deploy/k8s" "$WORK/tls"
  make_secrets "$WORK/tls"
  kubectl kustomize "$WORK/tls" > "$WORK/tls.yaml"
  /usr/bin/python3 "$CHECK" "$WORK/tls" --rendered "$WORK/tls.yaml"
  grep -q -- "--tls_cert=/etc/modskill/tls/tls.crt" "$WORK/tls.yaml" || { echo "FAIL: no --tls_cert in the TLS rendering"; exit 1; }
  # The plain-text variant README describes: no tls component, no modskill-tls secret.
  cp -r "$WORK/tls" "$WORK/plain"
  rm -r "$WORK/plain/tls"
  /usr/bin/python3 - "$WORK/plain/kustomization.yaml" <<'PY'
import sys, yaml
path = sys.argv[1]
k = yaml.safe_load(open(path))
del k["components"]
k["secretGenerator"] = [g for g in k["secretGenerator"] if g["name"] != "modskill-tls"]
yaml.safe_dump(k, open(path, "w"), sort_keys=False)
PY
  kubectl kustomize "$WORK/plain" > "$WORK/plain.yaml"
  /usr/bin/python3 "$CHECK" "$WORK/plain" --rendered "$WORK/plain.yaml"
  grep -q "grpc:" "$WORK/plain.yaml" || { echo "FAIL: the plain-text rendering has no native gRPC probe"; exit 1; }
  if grep -q "tls" "$WORK/plain.yaml"; then echo "FAIL: the plain-text rendering mentions tls"; exit 1; fi
  # The data-parallel variant: an indexed learner Job and the ranks' Service.
  cp -r "$WORK/tls" "$WORK/ranks"
  sed -i 's/^  - tls$/  - tls\n  - data-parallel/' "$WORK/ranks/kustomization.yaml"
  kubectl kustomize "$WORK/ranks" > "$WORK/ranks.yaml"
  /usr/bin/python3 "$CHECK" "$WORK/ranks" --rendered "$WORK/ranks.yaml"
  grep -q "completionMode: Indexed" "$WORK/ranks.yaml" || { echo "FAIL: no indexed Job in the data-parallel rendering"; exit 1; }
  grep -q -- "--rank=\$(MODSKILL_RANK)" "$WORK/ranks.yaml" || { echo "FAIL: no --rank in the data-parallel rendering"; exit 1; }
  echo "k8s render test: the three variants render and check"
}

case "${1:-}" in
  check) check ;;
  render) render ;;
  *) echo "usage: $0 check|render" >&2; exit 2 ;;
esac
