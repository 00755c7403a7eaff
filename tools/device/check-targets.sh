#!/usr/bin/env bash
# The core library builds for every no_std target it promises: no `std`, no alloc, only
# the `embedded-graphics` seam. Each target is built on its own so that one failure does
# not hide the others; the script exits 1 if any failed and says which.
#
#   tools/device/check-targets.sh [TARGET...]
set -uo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
targets=("$@")
(( ${#targets[@]} )) || targets=(thumbv6m-none-eabi thumbv7m-none-eabi thumbv7em-none-eabihf thumbv8m.main-none-eabihf riscv32imc-unknown-none-elf riscv32imac-unknown-none-elf)
installed="$(rustup target list --installed 2>/dev/null)"
failed=()
for t in "${targets[@]}"; do
    if ! grep -qx "$t" <<<"$installed"; then
        rustup target add "$t" || { failed+=("$t (target not installable)"); continue; }
    fi
    for features in "" "embedded-graphics"; do
        echo "--- cargo build --lib --no-default-features ${features:+--features $features }--target $t"
        if ! (cd "$root" && cargo build --quiet --lib --no-default-features ${features:+--features "$features"} --target "$t"); then
            failed+=("$t${features:+ +$features}")
        fi
    done
done
if (( ${#failed[@]} )); then
    printf 'check-targets.sh: FAILED: %s\n' "${failed[@]}" >&2
    exit 1
fi
echo "check-targets.sh: the core builds for ${targets[*]}"
