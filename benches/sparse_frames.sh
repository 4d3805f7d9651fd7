#!/usr/bin/env bash
# CPU time and peak memory of runs on small files of many nearly empty frames: 32,768 frames of
# a 256 x 256 Zebris plate (2^31 values, the default --max-values), written as gzipped XML:
#   empty.xml.gz    every frame empty (550 bytes)
#   dots.xml.gz     every frame one loaded sensel (13 KB)
#   patches.xml.gz  four frames a loaded 12 x 12 patch, the rest one sensel (13 KB)
# Usage: benches/sparse_frames.sh [PEDOMATCH] (default target/release/pedomatch).
set -euo pipefail
bin=$(realpath "${1:-target/release/pedomatch}")
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
python3 - "$dir" <<'PY'
import gzip, sys
head = (b"<measurement><cell_count><x>256</x><y>256</y></cell_count><movements><movement><clips>"
        b"<clip><cell_size><x>8.467</x><y>8.467</y></cell_size><frequency>100</frequency><data>")
tail = b"</data></clip></clips></movement></movements></measurement>"
dot = (b"<quant><cell_begin><x>5</x><y>7</y></cell_begin><cell_count><x>1</x><y>1</y></cell_count>"
       b"<cells>100</cells></quant>")
patch = (b"<quant><cell_begin><x>100</x><y>100</y></cell_begin><cell_count><x>12</x><y>12</y>"
         b"</cell_count><cells>" + b"100 " * 144 + b"</cells></quant>")
for name, body in [("empty", b"<quant/>" * 32768), ("dots", dot * 32768),
                   ("patches", patch * 4 + dot * 32764)]:
    open(f"{sys.argv[1]}/{name}.xml.gz", "wb").write(gzip.compress(head + body + tail, 9))
PY
printf '| file | model | exit | user CPU (s) | system CPU (s) | peak RSS (MB) |\n|---|---|---:|---:|---:|---:|\n'
for f in empty dots patches; do
    for model in contour surface isocontour; do
        [ "$f" != patches ] && [ "$model" != contour ] && continue
        set +e
        /usr/bin/time -f "%x %U %S %M" -o "$dir/t" "$bin" run "$dir/$f.xml.gz" --model "$model" \
            --out "$dir/out-$f-$model" >/dev/null 2>&1
        set -e
        read -r code user sys kb < <(tail -1 "$dir/t")
        printf '| %s | %s | %s | %s | %s | %d |\n' "$f.xml.gz" "$model" "$code" "$user" "$sys" $((kb / 1024))
    done
done
