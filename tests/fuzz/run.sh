#!/usr/bin/env bash
# Runs one libFuzzer harness for a few seconds over its seed corpus (and, for
# glTF, the real scenes in ../shared/scenes and the conformance set), then replays the regression
# inputs of crashes found before. Prints the executions; non-zero on a crash.
#   run.sh FUZZER NAME SOURCE_ROOT SECONDS
set -euo pipefail
start=$PWD
fuzzer=$(realpath "$1") name=$2 src=$3 secs=${4:-5}
work=$(mktemp -d)
# leaks inside the libraries a harness reads through (each named with its cause there)
export LSAN_OPTIONS=suppressions=$src/tests/fuzz/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}
# (a leak's stack through libstdc++ is cut short by the fast unwinder, before the frame a suppression names)
[[ $name == image ]] && export ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}fast_unwind_on_malloc=0
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/corpus"
cp "$src/tests/fuzz/corpus/$name"/* "$work/corpus/" 2>/dev/null || true
extra=()
if [[ $name == gltf ]]; then
  # the real scenes, and the conformance set (skins, instancing, alpha textures, quantization, sparse)
  for f in "$src"/../shared/scenes/*/*.glb "$src"/../shared/scenes/*/*.gltf "${SB_DATA_DIR:-.}"/conf-*.glb; do
    [[ -f $f ]] && cp "$f" "$work/corpus/"
  done
fi
if [[ -d $src/tests/fuzz/regressions/$name ]] && ls "$src/tests/fuzz/regressions/$name"/* >/dev/null 2>&1; then
  "$fuzzer" "$src/tests/fuzz/regressions/$name"/* 2>&1 | tail -n 3
fi
cd "$work"
dict=(); [[ -f $src/tests/fuzz/$name.dict ]] && dict=(-dict="$src/tests/fuzz/$name.dict")
"$fuzzer" "${dict[@]}" -max_total_time="$secs" -max_len=262144 -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
  corpus > log 2>&1 || {
    tail -n 40 log
    mkdir -p "$start/fuzz-crashes/$name" && cp crash-* leak-* timeout-* oom-* "$start/fuzz-crashes/$name/" 2>/dev/null || true
    echo "inputs kept in $start/fuzz-crashes/$name"
    exit 1
  }
grep -E "^stat::number_of_executed_units|^Done" log | head -n 2
echo "fuzz $name: ok"
