#!/usr/bin/env bash
# Proves that a refactor left the output tables of `pedomatch run` byte-identical: runs two builds
# on every committed recording under several option sets and compares their output folders.
#
#   scripts/compare-runs.sh OLD_PEDOMATCH NEW_PEDOMATCH
#
# Prints one line per case (`same  ...` or `DIFF  ...: files`), then `N passed, M failed`;
# exits 1 if any case differs or a run fails, 2 on a usage error. Needs jq.
set -euo pipefail

if [ $# -ne 2 ] || [ ! -x "$1" ] || [ ! -x "$2" ]; then
    echo "usage: $0 OLD_PEDOMATCH NEW_PEDOMATCH (two executable pedomatch binaries)" >&2
    exit 2
fi
command -v jq >/dev/null || { echo "$0: jq is needed to compare summary.json" >&2; exit 2; }

# Absolute binaries, then the repository root: the recordings are given by the same relative path
# to both binaries, because summary.json records the input path as given.
old=$(realpath "$1")
new=$(realpath "$2")
cd "$(dirname "$0")/.."

tmp=$(mktemp -d "${TMPDIR:-/tmp}/compare-runs.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

# name=path of each recording: the bundled walk, then every recording of benches/data (emed .lst,
# footscan .txt, pedar .asc, read with the bundled pedar layout; the uncommitted Pataky footscan
# file is included when present), named by its file name without the extension.
recordings=("walk=examples/data/FrasP01L.asf")
shopt -s nullglob
for f in benches/data/*.lst benches/data/*.txt benches/data/*.asc; do
    b=${f##*/}
    recordings+=("${b%.*}=$f")
done
shopt -u nullglob

# The option sets of `pedomatch run`; the empty one is the defaults. With figures or a report a run
# is held whole; the lean set (tables only) is streamed window by window: both ways are compared.
option_sets=("" "--model surface" "--model isocontour" "--drift-reference 25" "--tables parquet"
    "--figures none --report none")

# The files compared: every table and summary.json. Figures and report.html are not compared
# (the report embeds the run's timings).
is_compared() {
    case "$1" in *.csv | *.parquet | pairs.json | summary.json) return 0 ;; *) return 1 ;; esac
}

# summary.json without what differs between two runs of the same binary (found by diffing two
# runs of one binary into two folders): only `timings_s`, the seconds per stage. It names neither
# the output folder nor the binary; `pedomatch_version` is kept (a refactor should not change it).
# jq keeps the key order but re-prints the JSON: a change of whitespace alone would go unnoticed.
normalized_summary() {
    jq 'del(.timings_s)' "$1"
}

# run BINARY RECORDING OUT [OPTIONS...]: one run, its messages to OUT.log.
run() {
    local bin=$1 rec=$2 out=$3
    shift 3
    "$bin" run "$rec" --out "$out" "$@" >"$out.log" 2>&1
}

passed=0
failed=0
for entry in "${recordings[@]}"; do
    name=${entry%%=*}
    rec=${entry#*=}
    for opts in "${option_sets[@]}"; do
        label=${opts:-defaults}
        read -ra args <<<"$opts"
        rm -rf "$tmp"/old* "$tmp"/new*
        # One binary at a time: the runs use both cores and would only slow each other down.
        broken=
        run "$old" "$rec" "$tmp/old" "${args[@]}" || broken=old
        [ -n "$broken" ] || run "$new" "$rec" "$tmp/new" "${args[@]}" || broken=new
        if [ -n "$broken" ]; then
            echo "FAIL  $name $label: the $broken binary failed: $(tail -n 1 "$tmp/$broken.log")"
            failed=$((failed + 1))
            continue
        fi
        # Every file either folder has, so that a table missing from one side is a difference.
        diffs=()
        compared=0
        while IFS= read -r f; do
            is_compared "${f##*/}" || continue
            compared=$((compared + 1))
            if [ ! -f "$tmp/old/$f" ]; then
                diffs+=("$f (only in new)")
            elif [ ! -f "$tmp/new/$f" ]; then
                diffs+=("$f (only in old)")
            elif [ "$f" = summary.json ]; then
                # Through files, so that a summary jq cannot parse is a difference, not "same".
                normalized_summary "$tmp/old/$f" >"$tmp/old.summary" \
                    && normalized_summary "$tmp/new/$f" >"$tmp/new.summary" \
                    && cmp -s "$tmp/old.summary" "$tmp/new.summary" || diffs+=("$f")
            else
                cmp -s "$tmp/old/$f" "$tmp/new/$f" || diffs+=("$f")
            fi
        done < <(cd "$tmp" && find old new -type f | cut -d/ -f2- | sort -u)
        # Two empty folders are no proof: a run must write its tables.
        [ "$compared" -gt 0 ] || diffs+=("no tables written")
        if [ ${#diffs[@]} -eq 0 ]; then
            echo "same  $name $label"
            passed=$((passed + 1))
        else
            list=$(printf '%s, ' "${diffs[@]}")
            echo "DIFF  $name $label: ${list%, }"
            failed=$((failed + 1))
        fi
    done
done

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
