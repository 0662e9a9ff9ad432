#!/bin/bash
# compare.sh OLD_BIN NEW_BIN GRAPH... : decisions, final cost and time of
# `optimize` with the defaults, old build beside new, alternating.
old=$1; new=$2; shift 2
work=$(mktemp -d)
printf "%-28s %8s %8s %12s %12s %s\n" graph old_s new_s old_cost new_cost decisions
for g in "$@"; do
  name=$(basename "$(dirname "$g")")/$(basename "$g" .g2o)
  for b in old new; do
    bin=${!b}
    /usr/bin/time -f "%e" -o "$work/$b.time" "$bin" optimize "$g" -o "$work/$b.g2o" --json > "$work/$b.json" 2>/dev/null
    grep "^#CATGRAPH_DECISION" "$work/$b.g2o" | cut -d" " -f1-2 > "$work/$b.dec"; grep "^#CATGRAPH_DECISION" "$work/$b.g2o" | cut -d" " -f3 > "$work/$b.w"
  done
  oc=$(python3 -c "import json;print('%.6g'%json.load(open('$work/old.json'))['final_cost'])")
  nc=$(python3 -c "import json;print('%.6g'%json.load(open('$work/new.json'))['final_cost'])")
  if cmp -s "$work/old.dec" "$work/new.dec"; then d="same ($(grep -c rejected "$work/new.dec") rejected of $(wc -l < "$work/new.dec"))"; else d="DIFFER: $(diff "$work/old.dec" "$work/new.dec" | grep -c '^>') lines"; fi
  d="$d, max weight change $(paste "$work/old.w" "$work/new.w" | awk 'BEGIN{m=0} {x=$1-$2; if (x<0) x=-x; if (x>m) m=x} END{printf "%.1g", m}')"
  printf "%-28s %8s %8s %12s %12s %s\n" "$name" "$(cat "$work/old.time")" "$(cat "$work/new.time")" "$oc" "$nc" "$d"
done
rm -rf "$work"
