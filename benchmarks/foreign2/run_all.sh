#!/bin/sh
# Generate one run of every case into ${1:-/tmp/foreign2_check} and check each log.
PY=${PY:-python}
HERE=$(cd "$(dirname "$0")" && pwd)
OUT=${1:-/tmp/foreign2_check}
mkdir -p "$OUT"
i=0
for c in $($PY "$HERE/gen.py" --list | awk 'NR>1{print $1}'); do
  i=$((i+1))
  lat=$(awk -v i=$i 'BEGIN{printf "%.3f", 0.03 + (i*37 % 17)/100}')
  $PY "$HERE/gen.py" "$c" --seed $((100+i)) --latency "$lat" --out "$c" --outdir "$OUT" > "$OUT/$c.gen.json" || echo "GEN FAILED $c"
done
