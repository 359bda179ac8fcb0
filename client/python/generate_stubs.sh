#!/usr/bin/env bash
# Regenerates the committed protocol modules client/python/modskill/v1/modskill_pb2{,_grpc}.py
# from proto/modskill/v1/modskill.proto with Debian's protoc and grpc_python_plugin
# (apt install protobuf-compiler protobuf-compiler-grpc).
#
#   client/python/generate_stubs.sh            # rewrites client/python/modskill/v1/
#   client/python/generate_stubs.sh OUT_DIR    # writes OUT_DIR/modskill/v1/ instead (the drift test)
#
# Why committed rather than generated at install time: `pip install ./client/python` must work
# on a machine without protoc, the gRPC plugin or the C++ build tree (a client-only machine
# with python3-grpcio and python3-numpy), offline, with plain setuptools. The copies cannot drift:
# tests/python/test_install.py runs this script into a scratch directory and fails when the
# output differs from what is committed.
set -euo pipefail
REPO_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
OUT_DIR=${1:-}
for tool in protoc grpc_python_plugin; do
  command -v "$tool" >/dev/null || { echo "generate_stubs: no $tool (apt install protobuf-compiler protobuf-compiler-grpc)" >&2; exit 1; }
done
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/modskill-stubs.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT
protoc --proto_path="$REPO_DIR/proto" --python_out="$SCRATCH" --grpc_python_out="$SCRATCH" \
  --plugin=protoc-gen-grpc_python="$(command -v grpc_python_plugin)" "$REPO_DIR/proto/modskill/v1/modskill.proto"
DEST=${OUT_DIR:-$REPO_DIR/client/python}/modskill/v1
mkdir -p "$DEST"
cp "$SCRATCH/modskill/v1/modskill_pb2.py" "$SCRATCH/modskill/v1/modskill_pb2_grpc.py" "$DEST/"
