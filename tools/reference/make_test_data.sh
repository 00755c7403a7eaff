#!/usr/bin/env bash
# Regenerates the committed references tests/data/<name>.ref.pfm (full image) and
# <name>.ref.caustic.pfm (caustic part, L S+ D S* E), 320x240: renders seeds 1 and 2 (or
# $SEEDS; two at a time, one per core), commits their mean and writes its noise (the
# seeds' variance over their number; the first two seeds' pair figures) with the runs'
# statistics to tests/data/<name>.ref.json.
# Usage: [PHOTONS=20000000] [SEEDS="1 2"] [SCENES="glass_sphere two_balls ..."] [ARGS="--spp-max 1024"] tools/reference/make_test_data.sh
#   scene names are scenes/<name>.json or scenes/heldout/<name>.json; intermediate parts go
#   to $OUT (default /tmp/caustic-reference).
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
PHOTONS="${PHOTONS:-20000000}"
OUT="${OUT:-${TMPDIR:-/tmp}/caustic-reference}"
SCENES="${SCENES:-glass_sphere two_balls tube mirror_lens sphere_wall tilted_cube balls_mirror_tube}"
ARGS="${ARGS:-}"  # extra arguments for run, e.g. "--spp-max 1024"
mkdir -p "$REPO/tests/data" "$OUT"
SEEDS="${SEEDS:-1 2}"
read -r -a seeds <<<"$SEEDS"
(( ${#seeds[@]} >= 2 )) || { echo "make_test_data.sh: SEEDS needs two seeds or more" >&2; exit 2; }
for s in $SCENES; do
  f="$REPO/scenes/$s.json"
  [[ -f "$f" ]] || f="$REPO/scenes/heldout/$s.json"
  prefixes=()
  for i in "${!seeds[@]}"; do
    seed=${seeds[$i]}
    pre="$OUT/$s.s$seed"
    prefixes+=("$pre")
    ( start=$(date +%s)
      "$HERE/run" "$f" -o "$pre.pfm" --parts-prefix "$pre" --json "$pre.json" \
        --photons "$PHOTONS" --seed "$seed" $ARGS 2> "$pre.log"
      echo "$s seed $seed: $(( $(date +%s) - start ))s wall" ) &
    (( i % 2 == 1 )) && wait  # two at a time: one per core
  done
  wait
  "$HERE/run" --check --skip-analytic --pair "${prefixes[@]}" \
    --mean-to "$REPO/tests/data/$s.ref" --json "$REPO/tests/data/$s.ref.json"
done
