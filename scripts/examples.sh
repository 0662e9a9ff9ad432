#!/usr/bin/env bash
# Installs a built catgraph into a prefix, builds examples/ against the
# installed package as a user's project would, and runs each example,
# checking what it prints (README.md, examples/README.md).
#
#   bash scripts/examples.sh [BUILD_DIR]
#
# BUILD_DIR: a configured and built catgraph (default build). The prefix is
# BUILD_DIR/install, the examples' build BUILD_DIR/examples; both are made
# afresh. Exits non-zero when any step or check fails.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="$(cd "${1:-$root/build}" && pwd)"
prefix="$build_dir/install"
examples="$build_dir/examples"
work="$examples/work"

rm -rf "$prefix" "$examples"
cmake --install "$build_dir" --prefix "$prefix" >/dev/null
cmake -S "$root/examples" -B "$examples" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$examples" -j "${CATGRAPH_JOBS:-2}" >/dev/null
mkdir -p "$work"

# expect NAME TEXT FILE: FILE must hold TEXT (a fixed string).
expect() {
  if ! grep -qF -- "$2" "$3"; then
    echo "examples: $1 did not print '$2'; it printed:" >&2
    cat "$3" >&2
    exit 1
  fi
}

catgraph="$prefix/bin/catgraph"
"$examples/false_closure" > "$work/false_closure.txt"
expect false_closure "closure  0 -> 16: switch 1.000, accepted" "$work/false_closure.txt"
expect false_closure "closure  2 -> 22: switch 0.0" "$work/false_closure.txt"
expect false_closure "rejected" "$work/false_closure.txt"

"$catgraph" generate-graph -o "$work/world.g2o" --poses 500 --seed 1 >/dev/null
"$catgraph" inject "$work/world.g2o" -o "$work/world-outliers.g2o" --outliers 20 --seed 3 >/dev/null
"$examples/solve_g2o" "$work/world-outliers.g2o" "$work/solved.g2o" > "$work/solve_g2o.txt"
expect solve_g2o "20 rejected" "$work/solve_g2o.txt"
expect solve_g2o "#CATGRAPH_DECISION rejected" "$work/solved.g2o"

"$catgraph" simulate --scenario "$root/tests/fixtures/office-change-short.yaml" -o "$work/office" --quiet >/dev/null
"$examples/localize_dataset" "$work/office" > "$work/localize_dataset.txt"
expect localize_dataset "625 frames:" "$work/localize_dataset.txt"
if ! awk '/visual +frame/ {n++; e = $7; sub(/^\(/, "", e); if (e + 0 > 1.0) bad++}
          END {exit !(n >= 20 && bad == 0)}' "$work/localize_dataset.txt"; then
  echo "examples: localize_dataset: expected at least 20 visual closures, none over 1 m from the true place:" >&2
  cat "$work/localize_dataset.txt" >&2
  exit 1
fi
"$examples/stream_mapper" "$work/office" > "$work/stream_mapper.txt"
expect stream_mapper "625 frames," "$work/stream_mapper.txt"
# Closures reported as they come, and the last online solve's map at least
# twice as good as odometry alone.
if ! awk '/visual +closure/ {v++} /inferred +closure/ {i++} /map re-solved/ {ate = $NF + 0}
          END {exit !(v >= 20 && i >= 20 && ate > 0 && ate < 0.3)}' \
     <(sed 's/ m$//' "$work/stream_mapper.txt"); then
  echo "examples: stream_mapper: expected >= 20 visual and inferred closures and a final online ATE under 0.3 m:" >&2
  tail -5 "$work/stream_mapper.txt" >&2
  exit 1
fi
# The Python package as installed, by Debian's interpreter.
python_path="$prefix/lib/python3/dist-packages"
PYTHONPATH="$python_path" /usr/bin/python3 "$root/examples/robust_solve.py" > "$work/robust_solve.txt"
if ! awk '$1 == "switchable" && $3 == "1.000" && $4 == "1.000" {found = 1} END {exit !found}' "$work/robust_solve.txt"; then
  echo "examples: robust_solve.py: expected switchable at precision and recall 1.000:" >&2
  cat "$work/robust_solve.txt" >&2
  exit 1
fi
PYTHONPATH="$python_path" /usr/bin/python3 "$root/examples/robust_solve.py" "$work/world-outliers.g2o" \
  "$work/solved-python.g2o" > "$work/robust_solve_file.txt"
expect robust_solve.py "20 rejected" "$work/robust_solve_file.txt"
echo "examples: installed to $prefix; solve_g2o, false_closure, localize_dataset and stream_mapper built against it and ran;" \
  "robust_solve.py ran on the installed Python package"
