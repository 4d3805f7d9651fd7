# Sourced by the benches that run long recordings (lean.sh, memory.sh): `repeat_walk K OUT`
# writes the bundled F-Scan walk (`$walk`, an .asf) repeated K times to OUT: its header with
# END_FRAME set to the new count, its 205 frames K times renumbered, its end.
repeat_walk() {
  local k=$1 out=$2
  awk -v k="$k" '
    /^ASCII_DATA/ { header = header $0 "\n"; inbody = 1; next }
    !inbody { if ($0 ~ /^END_FRAME/) { sub(/[0-9]+/, "@END@") } header = header $0 "\n"; next }
    /^@@/ { tail = $0 "\n"; next }
    /^Frame / { n++ }
    { body[n] = body[n] $0 "\n" }
    END {
      nf = n; gsub(/@END@/, nf * k, header); printf "%s", header; printf "%s", body[0]
      m = 0
      for (r = 0; r < k; r++) for (f = 1; f <= nf; f++) {
        m++; b = body[f]; sub(/^Frame [0-9]+/, "Frame " m, b); printf "%s", b
      }
      printf "%s", tail
    }' "$walk" >"$out"
}
