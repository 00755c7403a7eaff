#!/usr/bin/env bash
# caustic on four instruction sets under QEMU, end to end: the single entry point CI calls.
#
#  1. builds the core for every no_std target (check-targets.sh);
#  2. builds the firmware examples/device (release) for each of
#       cortex-m4f  thumbv7em-none-eabihf      qemu-system-arm     -machine mps2-an386 (hard float)
#       cortex-m3   thumbv7m-none-eabi         qemu-system-arm     -machine mps2-an385 (soft float)
#       cortex-m33  thumbv8m.main-none-eabihf  qemu-system-arm     -machine mps2-an505 (Armv8-M)
#       rv32imac    riscv32imac-unknown-none-elf qemu-system-riscv32 -machine virt  (soft float)
#     twice: for Fig. 6, and with --features glass,error-estimate for the physical scene
#     (NAME-glass; it also prints the render's estimate of its own error);
#     and the QEMU plugin insn_plugin.so (counts instructions; any guest architecture);
#  3. runs each under QEMU (semihosting, 300 s time-out): it renders its scene at 160x120
#     row by row into OUT/NAME.rgb565 (RGB565, little-endian) and prints a PASS line with
#     the FNV-1a of those bytes;
#  4. converts the Cortex-M4F images to OUT/fig6.png and OUT/glass.png;
#  5. runs the host test tests/device.rs against the Cortex-M4F firmwares' bytes,
#     hashes and printed error estimates (host == device bit for bit and digit for
#     digit, and both == the committed values); the other firmwares' files and
#     estimates must equal those byte for byte;
#  6. prints each firmware's budget (budget.sh; Fig. 6 on the Cortex-M4F must meet its
#     bars) and the Cortex-M4F instruction profile;
#  7. ends with one JSON line per firmware:
#     {"firmware","target","flash_bytes","static_ram_bytes","stack_bytes","photon_bytes",
#      "forward_instructions","render_instructions","bit_identical"}.
#
#   tools/device/run.sh [--update-png] [--skip-targets] [--only NAME]   (NAME e.g. cortex-m4f-glass)
#
# OUT is examples/device/target/run (git-ignored); CAUSTIC_DEVICE_OUT overrides it
# (no spaces or commas: the path travels in QEMU's -semihosting-config). Exits non-zero
# on any failure, time-out, or difference between a device and the host.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
fw="$root/examples/device"
out="${CAUSTIC_DEVICE_OUT:-$fw/target/run}"
update_png=0
skip_targets=0
only=""
while (( $# )); do
    case "$1" in
        --update-png) update_png=1 ;;
        --skip-targets) skip_targets=1 ;;
        --only) only="${2:?--only needs a firmware name}"; shift ;;
        *) echo "usage: $0 [--update-png] [--skip-targets] [--only NAME]" >&2; exit 2 ;;
    esac
    shift
done
case "$out" in *[[:space:],]*) echo "run.sh: output path must not contain spaces or commas: $out" >&2; exit 2 ;; esac
start=$(date +%s)
step() { echo; echo "==> $*"; }

# name target qemu machine-and-cpu-flags scene (fig6 | glass: cargo feature)
boards=(
    "cortex-m4f|thumbv7em-none-eabihf|qemu-system-arm|-machine mps2-an386 -cpu cortex-m4"
    "cortex-m3|thumbv7m-none-eabi|qemu-system-arm|-machine mps2-an385 -cpu cortex-m3"
    "cortex-m33|thumbv8m.main-none-eabihf|qemu-system-arm|-machine mps2-an505 -cpu cortex-m33"
    "rv32imac|riscv32imac-unknown-none-elf|qemu-system-riscv32|-machine virt -bios none"
)
firmwares=()
for scene in fig6 glass; do
    for b in "${boards[@]}"; do
        name="${b%%|*}"
        [[ $scene == glass ]] && name="$name-glass"
        firmwares+=("$name|${b#*|}|$scene")
    done
done
if [[ -n "$only" ]]; then
    keep=()
    for f in "${firmwares[@]}"; do [[ "${f%%|*}" == "$only" ]] && keep+=("$f"); done
    (( ${#keep[@]} )) || { echo "run.sh: no firmware named $only" >&2; exit 2; }
    firmwares=("${keep[@]}")
fi

# --- tools -------------------------------------------------------------------------
"$root/tools/device/install-qemu"
installed="$(rustup target list --installed 2>/dev/null)"
for f in "${firmwares[@]}"; do
    IFS='|' read -r _ target _ _ _ <<<"$f"
    grep -qx "$target" <<<"$installed" || rustup target add "$target"
done
host="$(rustc -vV | sed -n 's/^host: //p')"
bin="$(rustc --print sysroot)/lib/rustlib/$host/bin"
[[ -x "$bin/llvm-objdump" ]] || rustup component add llvm-tools
cc="${CC:-cc}"
command -v "$cc" >/dev/null || { echo "run.sh: a C compiler ($cc) is needed for the QEMU plugin" >&2; exit 1; }
mkdir -p "$out"

# --- 1. the core on every no_std target -------------------------------------------------
if (( ! skip_targets )); then
    step "core on no_std targets (tools/device/check-targets.sh)"
    "$root/tools/device/check-targets.sh"
fi

# --- 2. plugin ---------------------------------------------------------------------------
"$cc" -O2 -shared -fPIC -fvisibility=hidden -Wall -Wextra -Werror \
    -o "$out/insn_plugin.so" "$root/tools/device/insn_plugin.c"

# --- 2-3. each firmware: build, run ------------------------------------------------------
for f in "${firmwares[@]}"; do
    IFS='|' read -r name target qemu machine scene <<<"$f"
    step "$name: building for $target (release, scene $scene)"
    features=()
    [[ $scene == glass ]] && features=(--features glass,error-estimate)
    (cd "$fw" && CARGO_TARGET_DIR="$fw/target" cargo build --release --target "$target" "${features[@]}")
    # The next build of this target overwrites the ELF: keep this one under its name.
    elf="$out/$name.elf"
    cp "$fw/target/$target/release/caustic-device" "$elf"
    step "$name: running under $qemu $machine"
    marks=$("$bin/llvm-nm" "$elf" | awk '/ caustic_mark_/ { printf ",mark=0x%s", $1 }')
    [[ $(tr -cd ',' <<<"$marks" | wc -c) == 4 ]] || { echo "run.sh: phase marks not found in $elf" >&2; exit 1; }
    rm -f "$out/$name.rgb565" "$out/$name.insn.txt"
    status=0
    # shellcheck disable=SC2086 # $machine is a list of flags
    timeout 300 "$qemu" $machine -nographic -monitor none -serial none \
        -semihosting-config "enable=on,target=native,arg=caustic,arg=$out/$name.rgb565" \
        -plugin "$out/insn_plugin.so,out=$out/$name.insn.txt$marks" \
        -kernel "$elf" | tee "$out/$name.log" || status=$?
    if (( status != 0 )); then
        (( status == 124 )) && echo "run.sh: $name: QEMU timed out after 300 s" >&2
        echo "run.sh: $name: the firmware failed (exit $status)" >&2
        exit 1
    fi
    grep -q '^PASS fnv1a=0x' "$out/$name.log" || { echo "run.sh: $name: no PASS line" >&2; exit 1; }
    [[ -s "$out/$name.rgb565" ]] || { echo "run.sh: $name: the firmware wrote no image" >&2; exit 1; }
done

# --- 4. PNG ----------------------------------------------------------------------------
first_of() { # scene: the first firmware of that scene
    for f in "${firmwares[@]}"; do [[ "${f##*|}" == "$1" ]] && { echo "${f%%|*}"; return; }; done
}
scenes=()
for f in "${firmwares[@]}"; do
    s="${f##*|}"; [[ " ${scenes[*]} " == *" $s "* ]] || scenes+=("$s")
done
for s in "${scenes[@]}"; do
    first=$(first_of "$s")
    python3 "$root/tools/device/rgb565_to_png.py" "$out/$first.rgb565" "$out/$s.png" 160 120
    echo "image: $out/$s.png"
    if (( update_png )); then
        cp "$out/$s.png" "$fw/$s-qemu.png"
        echo "updated examples/device/$s-qemu.png"
    elif ! cmp -s "$out/$s.png" "$fw/$s-qemu.png"; then
        echo "note: examples/device/$s-qemu.png differs from this run's image (--update-png to refresh)"
    fi
done

# --- 5. the host renders the same bytes ---------------------------------------------------
step "host render vs device bytes (cargo test --test device)"
envs=()
for s in "${scenes[@]}"; do
    first=$(first_of "$s")
    tag=$(tr '[:lower:]' '[:upper:]' <<<"$s")
    fnv=$(sed -n 's/^PASS fnv1a=\(0x[0-9a-f]*\).*/\1/p' "$out/$first.log")
    envs+=("CAUSTIC_DEVICE_${tag}_RGB565=$out/$first.rgb565" "CAUSTIC_DEVICE_${tag}_FNV1A=$fnv")
    error=$(sed -n 's/^error_estimate //p' "$out/$first.log")
    if [[ -n "$error" ]]; then
        envs+=("CAUSTIC_DEVICE_${tag}_ERROR=$error")
    elif [[ $s == glass ]]; then
        echo "run.sh: $first printed no error_estimate line" >&2; exit 1
    fi
done
(cd "$root" && env "${envs[@]}" cargo test --test device -- --nocapture --test-threads 1) 2>&1 \
    | tee "$out/host-test.log"
for s in "${scenes[@]}"; do
    tag=$(tr '[:lower:]' '[:upper:]' <<<"$s")
    grep -q "^$tag: device file .* is bit-identical to the host render" "$out/host-test.log" \
        || { echo "run.sh: the host test did not compare the device's $s bytes" >&2; exit 1; }
    if [[ $s == glass ]]; then
        grep -q "^$tag: the device's error estimate is the host's" "$out/host-test.log" \
            || { echo "run.sh: the host test did not compare the device's $s error estimate" >&2; exit 1; }
    fi
done
photon_bytes=$(sed -n 's/.*size_of Photon: \([0-9]*\) bytes$/\1/p' "$out/host-test.log")

# --- 6-7. budgets, profile, one JSON line per firmware ----------------------------------
lines=()
for f in "${firmwares[@]}"; do
    IFS='|' read -r name target _ _ scene <<<"$f"
    elf="$out/$name.elf"
    first=$(first_of "$scene")
    identical=false
    cmp -s "$out/$name.rgb565" "$out/$first.rgb565" \
        && [[ "$(grep '^error_estimate' "$out/$name.log")" == "$(grep '^error_estimate' "$out/$first.log")" ]] \
        && identical=true
    step "$name: budget"
    # Issue 14's bars are Fig. 6's on the Cortex-M4F: missed there, the run fails (session
    # 34's first corner lines went over two of them unnoticed; the others only report).
    strict=0
    [[ "$name" == cortex-m4f ]] && strict=1
    CAUSTIC_BUDGET_STRICT=$strict "$root/tools/device/budget.sh" "$elf" "$out/$name.log" \
        "$out/$name.insn.txt" | tee "$out/$name.budget.txt"
    eval "$(sed -n 's/^json_\([a-z_]*\)=\([0-9]*\)$/\1=\2/p' "$out/$name.budget.txt")"
    lines+=("$(printf '{"firmware": "%s", "target": "%s", "flash_bytes": %d, "static_ram_bytes": %d, "stack_bytes": %d, "photon_bytes": %d, "forward_instructions": %d, "render_instructions": %d, "bit_identical": %s}' \
        "$name" "$target" "$flash" "$ram" "$stack" "$photon_bytes" "$photons" "$render" "$identical")")
    [[ "$identical" == true ]] || { echo "run.sh: $name's image or error estimate differs from $first's" >&2; printf '%s\n' "${lines[@]}"; exit 1; }
done
first="${firmwares[0]%%|*}"
step "$first: instruction profile (tools/device/profile.py)"
python3 "$root/tools/device/profile.py" --top 8 "$out/$first.elf" \
    "$out/$first.insn.txt" | tee "$out/profile.txt"

echo
echo "run.sh: PASS (every device bit-identical to the host) in $(( $(date +%s) - start )) s"
printf '%s\n' "${lines[@]}"
