#!/usr/bin/env bash
# Regenerates the committed references tests/data/<name>.ref.pfm (full image) and
# <name>.ref.caustic.pfm (caustic part, L S+ D S* E), 320x240: renders seeds 1 and 2 (in
# parallel, one per core), commits their mean and writes the seed-to-seed noise with both
# runs' statistics to tests/data/<name>.ref.json.
# Usage: [PHOTONS=20000000] [SCENES="glass_sphere two_balls ..."] [ARGS="--spp-max 1024"] tools/reference/make_test_data.sh
#   scene names are scenes/<name>.json or scenes/heldout/<name>.json; intermediate parts go
#   to $OUT (default /tmp/caustic-reference).
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
PHOTONS="${PHOTONS:-20000000}"
OUT="${OUT:-${TMPDIR:-/tmp}/caustic-reference}"
SCENES="${SCENES:-glass_sphere two_balls tube sphere_wall tilted_cube balls_mirror_tube}"
ARGS="${ARGS:-}"  # extra arguments for run, e.g. "--spp-max 1024"
mkdir -p "$REPO/tests/data" "$OUT"
for s in $SCENES; do
  f="$REPO/scenes/$s.json"
  [[ -f "$f" ]] || f="$REPO/scenes/heldout/$s.json"
  for seed in 1 2; do
    pre="$OUT/$s.s$seed"
    ( start=$(date +%s)
      "$HERE/run" "$f" -o "$pre.pfm" --parts-prefix "$pre" --json "$pre.json" \
        --photons "$PHOTONS" --seed "$seed" $ARGS 2> "$pre.log"
      echo "$s seed $seed: $(( $(date +%s) - start ))s wall" ) &
  done
  wait
  "$HERE/run" --check --skip-analytic --pair "$OUT/$s.s1" "$OUT/$s.s2" \
    --mean-to "$REPO/tests/data/$s.ref" --json "$REPO/tests/data/$s.ref.json"
done
