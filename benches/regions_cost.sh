#!/usr/bin/env bash
# The cost of `--region-rule coarse` in a lean run (tables only, streamed where the model
# streams) of a long recording: the bundled F-Scan walk repeated K times (default 20), contour
# and surface models, with and without the regions, two builds side by side in alternating
# rounds. Prints one line per run: build, model, regions, CPU time (user + system, s), peak RSS
# (MB), whether the run streamed; then the median of each case's rounds as a Markdown table.
#
# Usage: benches/regions_cost.sh OLD_PEDOMATCH NEW_PEDOMATCH [K] [ROUNDS]
#        (ROUNDS default 3). Needs GNU time (/usr/bin/time).
set -euo pipefail
old=$(realpath "$1")
new=$(realpath "$2")
k=${3:-20}
rounds=${4:-3}
walk=$(realpath crates/pedo-io/tests/data/FrasP01L.asf)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
source "$(dirname "$0")/repeat_walk.sh"
rec="$tmp/walk_x$k.asf"
repeat_walk "$k" "$rec"
for r in $(seq "$rounds"); do
  for build in old new; do
    bin=$old
    [ "$build" = new ] && bin=$new
    for model in contour surface; do
      for regions in "" "--region-rule coarse"; do
        /usr/bin/time -f "%U %S %M" -o "$tmp/time" "$bin" run "$rec" --out "$tmp/out" \
          --figures none --report none --model "$model" $regions >/dev/null
        read -r user sys rss <"$tmp/time"
        streamed=$(jq -r .input.streamed "$tmp/out/summary.json")
        printf "%s|%s|%s|%.2f|%.1f|%s\n" "$build" "$model" "${regions:-none}" \
          "$(echo "$user + $sys" | bc -l)" "$(echo "$rss / 1024" | bc -l)" "$streamed"
        rm -rf "$tmp/out"
      done
    done
  done
done | tee "$tmp/rows"
echo
echo "| build | model | regions | streamed | CPU (s) | peak RSS (MB) |"
echo "|---|---|---|---|---:|---:|"
sort -t'|' -k1,3 "$tmp/rows" | awk -F'|' '
  function median(s,   a, n, i, j, t) {
    n = split(s, a, " ")
    for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (a[j] < a[i]) { t = a[i]; a[i] = a[j]; a[j] = t }
    return a[int((n + 1) / 2)]
  }
  { key = $1 "|" $2 "|" $3; cpu[key] = cpu[key] " " $4; rss[key] = rss[key] " " $5; st[key] = $6 }
  END { for (key in cpu) { split(key, p, "|")
    printf "| %s | %s | %s | %s | %.2f | %.1f |\n", p[1], p[2], p[3], st[key], median(cpu[key]), median(rss[key]) } }' | sort
