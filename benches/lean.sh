#!/usr/bin/env bash
# Default outputs (figures and report) of `pedomatch run` on the bundled F-Scan walk repeated
# 1x and 20x (205 -> 4,100 frames): folder and report.html size, files, wall time, time per
# frame and peak RSS; then a default `pedomatch batch` of the recordings in benches/data and,
# when EXTRA_DATA names a folder, in it too. Run with two builds to compare them side by side.
#
# Usage: benches/lean.sh PEDOMATCH [PEDOMATCH...]   (e.g. a build of main copied aside, and
#        target/release/pedomatch). Needs GNU time (/usr/bin/time). Prints Markdown tables.
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: $0 PEDOMATCH [PEDOMATCH...]" >&2; exit 2; }
walk=$(realpath crates/pedo-io/tests/data/FrasP01L.asf)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# repeat_walk K OUT: the walk repeated K times.
source "$(dirname "$0")/repeat_walk.sh"
for k in 1 20; do repeat_walk "$k" "$tmp/walk_x$k.asf"; done

mb() { awk -v b="$1" 'BEGIN { printf "%.1f", b / 1048576 }'; }

echo "| build | walk | frames | files | folder (MB) | report.html (MB) | wall time (s) | ms per frame | peak RSS (MB) |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|"
for bin in "$@"; do
  for k in 1 20; do
    out="$tmp/out"
    /usr/bin/time -f "%e %M" -o "$tmp/time" "$(realpath "$bin")" run "$tmp/walk_x$k.asf" --out "$out" >/dev/null
    read -r wall rss <"$tmp/time"
    frames=$(grep -m1 -o '"frames": [0-9][0-9]*' "$out/summary.json" | grep -o '[0-9]*$')
    files=$(find "$out" -type f ! -name '.pedomatch-output' | wc -l)
    folder=$(du -sb "$out" | cut -f1)
    report=$(stat -c %s "$out/report.html" 2>/dev/null || echo 0)
    printf "| %s | %sx | %d | %d | %s | %s | %.2f | %.2f | %.0f |\n" "$bin" "$k" "$frames" "$files" \
      "$(mb "$folder")" "$(mb "$report")" "$wall" "$(echo "$wall * 1000 / $frames" | bc -l)" "$(echo "$rss / 1024" | bc -l)"
    rm -rf "$out"
  done
done

inputs=(benches/data)
if [ -n "${EXTRA_DATA:-}" ]; then inputs+=("$EXTRA_DATA"); fi
echo
echo "| build | recordings | wall time (s) | peak RSS (MB) | files | folder (MB) |"
echo "|---|---:|---:|---:|---:|---:|"
for bin in "$@"; do
  out="$tmp/study"
  /usr/bin/time -f "%e %M" -o "$tmp/time" "$(realpath "$bin")" batch "${inputs[@]}" --out "$out" >/dev/null || true
  read -r wall rss <"$tmp/time"
  n=$(($(wc -l <"$out/study.csv") - 1))
  files=$(find "$out" -type f ! -name '.pedomatch-output' | wc -l)
  printf "| %s | %d | %.2f | %.0f | %d | %s |\n" "$bin" "$n" "$wall" "$(echo "$rss / 1024" | bc -l)" "$files" "$(mb "$(du -sb "$out" | cut -f1)")"
  rm -rf "$out"
done
echo
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
