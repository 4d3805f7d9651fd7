#!/usr/bin/env bash
# `pedomatch batch` across recordings: wall time with 1 and 2 jobs on 20 recordings (the speed-up),
# and peak RSS for 5 and 20 recordings (it should not grow with their number).
#
# Usage: benches/batch.sh [PEDOMATCH]   (default target/release/pedomatch; build it with
#        `cargo build --release` first). Needs GNU time (/usr/bin/time). Prints a Markdown table.
#
# The 20 recordings: 12 copies of the bundled F-Scan walk (205 frames) and 2 copies each of four
# test recordings (Tekscan CSV, footscan, emed, synthetic emed roll-over); 5 of them (3 walks,
# Tekscan CSV, emed) for the memory comparison. Tables only (--figures none --report none): the
# figures and the report scale the same way and would only lengthen the run.
set -euo pipefail
bin=$(realpath "${1:-target/release/pedomatch}")
data=$(realpath crates/pedo-io/tests/data)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

mkdir -p "$tmp/s20" "$tmp/s5"
for i in $(seq -w 1 12); do cp "$data/FrasP01L.asf" "$tmp/s20/walk_$i.asf"; done
for i in 1 2; do
  cp "$data/tekscan-FrasP01L-11-20.csv" "$tmp/s20/tekscan_$i.csv"
  cp "$data/footscan-FrasP01L-11-20.txt" "$tmp/s20/footscan_$i.txt"
  cp "$data/emed-test-1-10.lst" "$tmp/s20/emed_$i.lst"
  cp "$data/synthetic-walk.lst" "$tmp/s20/synthetic_$i.lst"
done
cp "$tmp"/s20/walk_0{1,2,3}.asf "$tmp/s20/tekscan_1.csv" "$tmp/s20/emed_1.lst" "$tmp/s5/"

# One batch run: prints "wall_s peak_rss_mb".
measure() {
  local set=$1 jobs=$2 out="$tmp/out-$1-$2"
  /usr/bin/time -f "%e %M" -o "$tmp/time" \
    "$bin" batch "$tmp/$set" --out "$out" --jobs "$jobs" --figures none --report none >/dev/null
  test "$(grep -c ',ok,' "$out/study.csv")" -eq "$(ls "$tmp/$set" | wc -l)"
  rm -rf "$out"
  awk '{printf "%.2f %.1f\n", $1, $2 / 1024}' "$tmp/time"
}

read -r t1 m1 < <(measure s20 1)
read -r t2 m2 < <(measure s20 2)
read -r t5 m5 < <(measure s5 2)
echo "| recordings | jobs | wall time (s) | peak RSS (MB) |"
echo "|---|---|---|---|"
echo "| 20 | 1 | $t1 | $m1 |"
echo "| 20 | 2 | $t2 | $m2 |"
echo "| 5 | 2 | $t5 | $m5 |"
echo
awk -v a="$t1" -v b="$t2" 'BEGIN { printf "speed-up 1 -> 2 jobs: %.2fx\n", a / b }'
awk -v a="$m2" -v b="$m5" 'BEGIN { printf "peak RSS 20 / 5 recordings (2 jobs): %.2f\n", a / b }'
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
