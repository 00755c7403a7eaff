#!/usr/bin/env bash
# The reference tool's own light tracer as a baseline for the time-versus-error
# benchmark: renders each reference scene at small photon budgets with another seed
# (2) than the committed references (1), and records wall time and the error against
# the committed reference, in docs/reference_baseline.csv (read by
# `cargo bench --bench time_vs_error`).
#
#   tools/reference/baseline.sh [BUDGETS...]     (default: 250000 1000000 4000000)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
budgets=("$@")
[[ ${#budgets[@]} -gt 0 ]] || budgets=(250000 1000000 4000000)
cargo build --release --quiet --bin caustic
caustic="$root/target/release/caustic"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
out="$root/docs/reference_baseline.csv"
echo "scene,photons,seconds,full_rel_rmse,caustic_rel_rmse" > "$out"
for scene in glass_sphere two_balls tube; do
    for n in "${budgets[@]}"; do
        start=$(date +%s.%N)
        tools/reference/run "scenes/$scene.json" -o "$tmp/b.pfm" --photons "$n" --seed 2 --no-splat >/dev/null
        end=$(date +%s.%N)
        json=$("$caustic" compare "$tmp/b.pfm" "tests/data/$scene.ref.pfm" \
            --mask "tests/data/$scene.ref.caustic.pfm" --mask-fraction 0.02)
        python3 - "$scene" "$n" "$start" "$end" "$json" >> "$out" <<'PY'
import json, sys
scene, n, start, end, text = sys.argv[1:]
d = json.loads(text)
print(f"{scene},{n},{float(end) - float(start):.3f},{d['rel_rmse']:.6f},{d['mask']['rel_rmse']:.6f}")
PY
        tail -1 "$out"
    done
done
