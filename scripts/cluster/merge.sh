#!/usr/bin/env bash
# Merges the shard folders written by shadowbench.sbatch (or the CI matrix)
# into OUT/merged: one results set equal to an unsharded run's.
set -euo pipefail
out=${1:?results folder of the shards}
bin=${SHADOWBENCH:-build-release/shadowbench}
mapfile -t dirs < <(ls -d "$out"/shard-*/*/*/)
"$bin" merge "${dirs[@]}" --out "$out/merged"
