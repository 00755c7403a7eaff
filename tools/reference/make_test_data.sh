#!/usr/bin/env bash
# Regenerates the committed reference images tests/data/<scene>.ref.pfm (+ .ref.caustic.pfm)
# at 160x120 (seed 1), renders a second seed into $OUT, and prints the self-checks and the
# seed-to-seed noise for each scene.
# Usage: [SCENES="glass_sphere two_balls tube"] tools/reference/make_test_data.sh [PHOTONS]
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
PHOTONS="${1:-100000000}"
OUT="${OUT:-${TMPDIR:-/tmp}/caustic-reference}"
mkdir -p "$REPO/tests/data" "$OUT"
for s in ${SCENES:-glass_sphere two_balls tube}; do
  for seed in 1 2; do
    pre="$OUT/$s.s$seed"
    start=$(date +%s)
    nice -n 10 "$HERE/run" "$REPO/scenes/$s.json" -o "$pre.pfm" --parts-prefix "$pre" \
      --width 160 --height 120 --photons "$PHOTONS" --seed "$seed" 2> "$pre.log"
    echo "$s seed $seed: $(( $(date +%s) - start ))s  $(tail -1 "$pre.log")"
  done
  cp "$OUT/$s.s1.pfm" "$REPO/tests/data/$s.ref.pfm"
  cp "$OUT/$s.s1.caustic.pfm" "$REPO/tests/data/$s.ref.caustic.pfm"
  "$HERE/run" --check --skip-analytic --pair "$OUT/$s.s1" "$OUT/$s.s2"
done
"$HERE/run" --check --pair "$OUT/glass_sphere.s1" "$OUT/glass_sphere.s2" | head -4
