#!/usr/bin/env bash
# A default `pedomatch batch` of one folder of recordings with two or more builds, side by side:
# the builds alternate, ROUNDS rounds (default 3), so that a shared machine's load falls on each
# alike. Per run: wall time, CPU time (user + system), peak RSS, files and the study folder's size.
#
# Usage: DATA=DIR benches/batch_speed.sh PEDOMATCH [PEDOMATCH...]   (ROUNDS=N to change the
#        rounds; ARGS="--figures none" etc. to add options to every run). DIR: the eight 500 Hz
#        footscan trials of `python benches/data/make_recordings.py --pataky-trials DIR`.
#        Needs GNU time (/usr/bin/time). Prints a Markdown table and the load average.
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: DATA=DIR $0 PEDOMATCH [PEDOMATCH...]" >&2; exit 2; }
data=$(realpath "${DATA:?DATA=DIR: the folder of recordings}")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mb() { awk -v b="$1" 'BEGIN { printf "%.1f", b / 1048576 }'; }

echo "| round | build | recordings | wall time (s) | CPU time (s) | peak RSS (MB) | files | folder (MB) |"
echo "|---:|---|---:|---:|---:|---:|---:|---:|"
for round in $(seq 1 "${ROUNDS:-3}"); do
  for bin in "$@"; do
    out="$tmp/study"
    # shellcheck disable=SC2086
    /usr/bin/time -f "%e %U %S %M" -o "$tmp/time" "$(realpath "$bin")" batch "$data" --out "$out" \
      ${ARGS:-} >/dev/null 2>&1 || true
    read -r wall user sys rss <"$tmp/time"
    n=$(($(wc -l <"$out/study.csv") - 1))
    files=$(find "$out" -type f ! -name '.pedomatch-*' | wc -l)
    printf "| %d | %s | %d | %.2f | %.2f | %.0f | %d | %s |\n" "$round" "$bin" "$n" "$wall" \
      "$(echo "$user + $sys" | bc -l)" "$(echo "$rss / 1024" | bc -l)" "$files" \
      "$(mb "$(du -sb "$out" | cut -f1)")"
    rm -rf "$out"
  done
done
echo
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
