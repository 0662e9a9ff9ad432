#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, AddressSanitizer + UndefinedBehaviorSanitizer)
# and runs each for a bounded time, two at a time (docs/fuzzing.md).
#
#   bash scripts/fuzz.sh [SECONDS] [TARGET...]
#
# SECONDS per target (default 60; 0 for no time limit); FUZZ_RUNS, when set,
# stops each target after that many executions instead (the long documented
# runs: FUZZ_RUNS=10000000 bash scripts/fuzz.sh 0), made of processes of at
# most FUZZ_CHUNK executions (default 100000). FUZZ_TIMEOUT: seconds of wall
# time one input may take (default 10; libFuzzer measures wall time, so a
# campaign at low priority on a busy machine needs more). TARGETs among graph trajectory scenario
# dataset import sweep vocabulary image (default all). The seed corpus is made from the
# project's own test fixtures, scenarios, sweep configurations and files the
# release build (build/apps/catgraph, when present) generates; each run grows
# build-fuzz/corpus/TARGET. A crash, leak, hang (> 10 s), out-of-memory
# (> 2 GB) or sanitizer report leaves its input in build-fuzz/artifacts/TARGET/
# and makes the script exit non-zero. FUZZ_BUILD_DIR names another build folder
# configured with clang and -DCATGRAPH_FUZZ=ON; FUZZ_SEED fixes libFuzzer's
# random seed (default 0: a new one each run). FUZZ_LANE names a second
# campaign on the same targets running beside the first (their own logs,
# TARGET-LANE.log; the corpus is shared, as with libFuzzer's -jobs). Expects
# scripts/setup.sh to have installed the packages (clang-14, libclang-rt-14-dev
# among them).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-60}"
shift || true
all=(graph trajectory scenario dataset import sweep vocabulary image)
targets=("$@")
[ "${#targets[@]}" -gt 0 ] || targets=("${all[@]}")
build_dir="${FUZZ_BUILD_DIR:-$root/build-fuzz}"
catgraph="$root/build/apps/catgraph"

if [ ! -f "$build_dir/CMakeCache.txt" ]; then
  CXX=clang++-14 cmake -S "$root" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DCATGRAPH_WERROR=ON \
    -DCATGRAPH_FUZZ=ON -DCATGRAPH_BUILD_TESTS=OFF -DCATGRAPH_BUILD_BENCH=OFF >/dev/null
fi
cmake --build "$build_dir" -j 2 --target "${targets[@]/%/_fuzzer}"

# seed TARGET PREFIX_BYTE FILE...: FILE with the reader-choosing first byte.
seed() {
  local target="$1" prefix="$2"; shift 2
  mkdir -p "$build_dir/corpus/$target"
  for f in "$@"; do
    [ -f "$f" ] || continue
    { printf "\\x$prefix"; cat "$f"; } > "$build_dir/corpus/$target/seed-$prefix-$(basename "$f")"
  done
}
generated="$build_dir/generated"
if [ -x "$catgraph" ] && [ ! -f "$generated/done-2" ]; then
  rm -rf "$generated" && mkdir -p "$generated"
  "$catgraph" generate-graph --poses 60 -o "$generated/graph.g2o" --truth "$generated/truth.g2o" >/dev/null
  "$catgraph" inject "$generated/graph.g2o" -o "$generated/spoiled.g2o" --outliers 5 --switchable \
    --labels "$generated/labels.csv" >/dev/null
  "$catgraph" export "$generated/truth.g2o" -o "$generated/truth.tum" >/dev/null
  "$catgraph" simulate --scenario office-change --frames 40 -o "$generated/dataset" --quiet >/dev/null
  "$catgraph" vocabulary train "$generated/dataset" -o "$generated/vocabulary.yml" --words 2 --every 2 \
    --iterations 3 --quiet >/dev/null
  touch "$generated/done-2"
fi
seed graph 00 "$root"/tests/fixtures/*.g2o "$generated/graph.g2o" "$generated/spoiled.g2o"
seed graph 04 "$root"/tests/fixtures/*.graph
seed trajectory 00 "$generated/truth.g2o" "$generated/truth.tum"
seed trajectory 04 "$generated/labels.csv"
seed scenario 00 "$root"/simulation/scenarios/*.yaml
for i in 0 1 2 3; do
  files=("$generated/dataset/frames.csv" "$generated/dataset/odometry.csv" \
         "$generated/dataset/groundtruth.csv" "$generated/dataset/meta.json")
  seed dataset "0$i" "${files[$i]}"
done
# The import target's files (its first byte picks which; fuzz_inputs.h).
mkdir -p "$build_dir/corpus/import"
printf '\x00%s' $'1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0.1\n1 0 0 0 0 1 0 0 0 0 1 0.2\n' > "$build_dir/corpus/import/seed-kitti-poses"
printf '\x01%s' $'0.0\n0.1\n0.2\n' > "$build_dir/corpus/import/seed-kitti-times"
printf '\x02%s' $'# ground truth\n0.0 0 0 0 0 0 0 1\n0.1 0 0 0.1 0 0 0 1\n0.2 0 0 0.2 0 0 0 1\n' > "$build_dir/corpus/import/seed-tum-truth"
printf '\x03%s' $'0.0 rgb/0.png\n0.1 rgb/1.png\n0.2 rgb/2.png\n' > "$build_dir/corpus/import/seed-tum-rgb"
seed import 04 "$generated/dataset/groundtruth.csv"
printf '\x05%s' $'0.0\n0.1\n0.2\n' > "$build_dir/corpus/import/seed-folder-times"
seed sweep 00 "$root"/docs/experiments/*.yaml
seed sweep 02 "$root"/docs/experiments/*.csv
seed vocabulary 00 "$generated/vocabulary.yml"
# Small PNGs and JPEGs of each layout (fuzz/seeds/image/), as they are.
mkdir -p "$build_dir/corpus/image" && cp "$root"/fuzz/seeds/image/* "$build_dir/corpus/image/"
# Inputs that once found a bug, as they are (they carry their first byte).
for t in "${all[@]}"; do
  if [ -d "$root/tests/fixtures/fuzz/$t" ]; then
    mkdir -p "$build_dir/corpus/$t" && cp "$root/tests/fixtures/fuzz/$t"/* "$build_dir/corpus/$t/"
  fi
done
# The scenario and vocabulary readers take the whole input as the file.
for t in scenario vocabulary; do
  for f in "$build_dir/corpus/$t"/seed-00-*; do [ -f "$f" ] && tail -c +2 "$f" > "$f.tmp" && mv "$f.tmp" "$f"; done
done

dict_of() {
  case "$1" in
    graph|trajectory) echo "-dict=$root/fuzz/graph.dict" ;;
    scenario|sweep) echo "-dict=$root/fuzz/yaml.dict" ;;
  esac
}
# The readers that take paths get their files in a scratch folder of each run's
# own, in memory where /dev/shm is writable (the disk was most of a dataset
# run), removed afterwards.
scratch_root=/dev/shm
[ -d "$scratch_root" ] && [ -w "$scratch_root" ] || scratch_root="${TMPDIR:-/tmp}"
# Inputs are bounded at 8 KB where the seeds would let them grow to 77 KB
# (sweep CSVs) or 19 KB (vocabularies): yaml-cpp's scanner is most of a run,
# and four times as many runs at 8 KB cover more than a few at 77 KB.
max_len_of() {
  case "$1" in
    sweep|vocabulary) echo "-max_len=8192" ;;
  esac
}
# One libFuzzer process for `seconds` (or FUZZ_RUNS executions); with
# FUZZ_RUNS, a chain of processes of at most FUZZ_CHUNK executions each
# (default 100000), every one starting from the corpus the last one grew: the
# sanitizer runtime's own memory grows by 2-8 KB per execution on the
# yaml-cpp targets (a release build of the same readers stays flat), one
# process of 10^7 executions would pass the 2 GB limit, and a process slows
# as it ages (docs/fuzzing.md).
log_of() { echo "$build_dir/$1${FUZZ_LANE:+-$FUZZ_LANE}.log"; }
run() {
  local t="$1" log scratch rc=0 remaining="${FUZZ_RUNS:--1}" chunk="${FUZZ_CHUNK:-100000}" runs done_now
  mkdir -p "$build_dir/artifacts/$t" "$build_dir/corpus/$t"
  log="$(log_of "$t")"
  : >"$log"
  while :; do
    runs="$remaining"
    if [ "$remaining" -gt 0 ] && [ "$remaining" -gt "$chunk" ]; then runs="$chunk"; fi
    scratch="$(mktemp -d "$scratch_root/catgraph-fuzz-$t.XXXXXX")"
    # shellcheck disable=SC2046
    TMPDIR="$scratch" "$build_dir/fuzz/${t}_fuzzer" -max_total_time="$seconds" -runs="$runs" -timeout="${FUZZ_TIMEOUT:-10}" -rss_limit_mb=2048 \
      -print_final_stats=1 -seed="${FUZZ_SEED:-0}" \
      -artifact_prefix="$build_dir/artifacts/$t/" $(dict_of "$t") $(max_len_of "$t") "$build_dir/corpus/$t" \
      >>"$log" 2>&1 || rc=$?
    rm -rf "$scratch"
    [ "$rc" -eq 0 ] && [ "$remaining" -gt 0 ] || break
    done_now=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$')
    remaining=$((remaining - done_now))
    [ "$remaining" -gt 0 ] || break
  done
  return "$rc"
}
status=0
pids=()
names=()
for t in "${targets[@]}"; do
  run "$t" & pids+=($!); names+=("$t")
  if [ "${#pids[@]}" -eq 2 ]; then
    wait "${pids[0]}" || status=1
    pids=("${pids[1]}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
printf '%-12s %14s %10s %s\n' target executions exec/s result
for t in "${targets[@]}"; do
  log="$(log_of "$t")"
  # Sums over the chain of processes; the rate is their mean.
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | awk '{s += $2} END {print s + 0}')
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | awk '{s += $2; n++} END {print n ? int(s / n) : 0}')
  if grep -qE 'ERROR: (libFuzzer|AddressSanitizer|LeakSanitizer|UndefinedBehaviorSanitizer)|runtime error:|Test unit written' "$log"; then
    result="FINDING: $log"
    status=1
  else
    result=ok
  fi
  printf '%-12s %14s %10s %s\n' "$t" "$runs" "$rate" "$result"
done
exit "$status"
