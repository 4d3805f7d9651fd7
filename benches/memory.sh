#!/usr/bin/env bash
# `pedomatch run` on the bundled F-Scan walk repeated 1x, 10x and 100x (205 -> 20,500 frames):
# wall time and peak RSS (a streamed run's peak should not grow with the recording's length).
#
# Usage: benches/memory.sh [PEDOMATCH] [REPEATS...]   (default target/release/pedomatch, 1 10 100;
#        build it with `cargo build --release` first). Needs GNU time (/usr/bin/time).
# Tables only (--figures none --report none), like benches/batch.sh; TABLES=parquet writes them
# as Parquet (default csv). Prints a Markdown table.
set -euo pipefail
bin=$(realpath "${1:-target/release/pedomatch}")
shift || true
repeats=("${@:-1 10 100}")
read -r -a repeats <<<"${repeats[*]}"
walk=$(realpath crates/pedo-io/tests/data/FrasP01L.asf)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# repeat_walk K OUT: the walk repeated K times.
source "$(dirname "$0")/repeat_walk.sh"

echo "| walk | frames | wall time (s) | peak RSS (MB) |"
echo "|---|---:|---:|---:|"
for k in "${repeats[@]}"; do
  rec="$tmp/walk_x$k.asf"
  repeat_walk "$k" "$rec"
  /usr/bin/time -f "%e %M" -o "$tmp/time" \
    "$bin" run "$rec" --out "$tmp/out" --figures none --report none --tables "${TABLES:-csv}" >/dev/null
  frames=$(grep -m1 -o '"frames": [0-9][0-9]*' "$tmp/out/summary.json" | grep -o '[0-9]*$')
  read -r wall rss <"$tmp/time"
  printf "| %sx | %d | %.2f | %.1f |\n" "$k" "$frames" "$wall" "$(echo "$rss / 1024" | bc -l)"
  rm -rf "$tmp/out"
done
