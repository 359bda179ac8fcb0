#!/usr/bin/env bash
# The main job: set up, build, then step a batch of humanoid tracking envs on the shipped
# motion library and print throughput. Extra arguments go to modskill-demo.
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/setup.sh
exec "${MODSKILL_BUILD_DIR:-build}/server/modskill-demo" --envs 256 --threads "$(nproc)" --steps 300 "$@"
