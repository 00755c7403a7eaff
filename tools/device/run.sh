#!/usr/bin/env bash
# caustic on a Cortex-M4F, end to end: the single entry point CI calls.
#
#  1. builds the core for every no_std target (check-targets.sh);
#  2. builds the firmware examples/cortex-m4 (release) and the QEMU plugin insn_plugin.so;
#  3. runs the firmware under QEMU (mps2-an386, Cortex-M4F, semihosting, 300 s time-out):
#     it renders Fig. 6 at 160x120 row by row into OUT/fig6.rgb565 (RGB565, little-endian)
#     and prints a PASS line with the FNV-1a of those bytes; the plugin counts instructions;
#  4. converts the image to OUT/fig6.png;
#  5. runs the host test tests/device.rs, which renders the same scene on the host and
#     asserts both the bytes and the hash are the device's, bit for bit;
#  6. prints the budget (budget.sh) and the instruction profile (profile.py).
#
#   tools/device/run.sh [--update-png] [--skip-targets]
#
# OUT is examples/cortex-m4/target/run (git-ignored); CAUSTIC_DEVICE_OUT overrides it
# (no spaces or commas: the path travels in QEMU's -semihosting-config). --update-png
# copies the PNG to examples/cortex-m4/fig6-qemu.png. Exits non-zero on any failure,
# time-out, or difference between device and host.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
fw="$root/examples/cortex-m4"
out="${CAUSTIC_DEVICE_OUT:-$fw/target/run}"
update_png=0
skip_targets=0
for arg in "$@"; do
    case "$arg" in
        --update-png) update_png=1 ;;
        --skip-targets) skip_targets=1 ;;
        *) echo "usage: $0 [--update-png] [--skip-targets]" >&2; exit 2 ;;
    esac
done
case "$out" in *[[:space:],]*) echo "run.sh: output path must not contain spaces or commas: $out" >&2; exit 2 ;; esac
start=$(date +%s)
step() { echo; echo "==> $*"; }

# --- tools -------------------------------------------------------------------------
if ! command -v qemu-system-arm >/dev/null; then
    if [[ $(id -u) == 0 ]] && command -v apt-get >/dev/null; then
        step "installing qemu-system-arm (Debian package)"
        apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq qemu-system-arm >/dev/null
    else
        echo "run.sh: qemu-system-arm is missing (Debian: apt-get install qemu-system-arm)" >&2; exit 1
    fi
fi
if ! rustup target list --installed 2>/dev/null | grep -qx thumbv7em-none-eabihf; then
    rustup target add thumbv7em-none-eabihf
fi
host="$(rustc -vV | sed -n 's/^host: //p')"
if [[ ! -x "$(rustc --print sysroot)/lib/rustlib/$host/bin/llvm-objdump" ]]; then
    rustup component add llvm-tools
fi
cc="${CC:-cc}"
command -v "$cc" >/dev/null || { echo "run.sh: a C compiler ($cc) is needed for the QEMU plugin" >&2; exit 1; }
mkdir -p "$out"

# --- 1. the core on every no_std target -------------------------------------------------
if (( ! skip_targets )); then
    step "core on no_std targets (tools/device/check-targets.sh)"
    "$root/tools/device/check-targets.sh"
fi

# --- 2. firmware and plugin ------------------------------------------------------------
step "building the firmware (release)"
(cd "$fw" && CARGO_TARGET_DIR="$fw/target" cargo build --release)
elf="$fw/target/thumbv7em-none-eabihf/release/caustic-cortex-m4"
"$cc" -O2 -shared -fPIC -fvisibility=hidden -Wall -Wextra -Werror \
    -o "$out/insn_plugin.so" "$root/tools/device/insn_plugin.c"

# --- 3. QEMU -------------------------------------------------------------------------
step "running under QEMU (mps2-an386, Cortex-M4F)"
nm="$(rustc --print sysroot)/lib/rustlib/$host/bin/llvm-nm"
marks=$("$nm" "$elf" | awk '/ caustic_mark_/ { printf ",mark=0x%s", $1 }')
[[ $(tr -cd ',' <<<"$marks" | wc -c) == 4 ]] || { echo "run.sh: phase marks not found in $elf" >&2; exit 1; }
rm -f "$out/fig6.rgb565" "$out/insn-profile.txt"
qemu_status=0
timeout 300 qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -nographic \
    -monitor none -serial none \
    -semihosting-config "enable=on,target=native,arg=caustic,arg=$out/fig6.rgb565" \
    -plugin "$out/insn_plugin.so,out=$out/insn-profile.txt$marks" \
    -kernel "$elf" | tee "$out/qemu.log" || qemu_status=$?
if (( qemu_status != 0 )); then
    (( qemu_status == 124 )) && echo "run.sh: QEMU timed out after 300 s" >&2
    echo "run.sh: the firmware failed (exit $qemu_status)" >&2
    exit 1
fi
fnv=$(sed -n 's/^PASS fnv1a=\(0x[0-9a-f]*\).*/\1/p' "$out/qemu.log")
[[ -n "$fnv" ]] || { echo "run.sh: no PASS line from the firmware" >&2; exit 1; }
[[ -s "$out/fig6.rgb565" ]] || { echo "run.sh: the firmware wrote no image" >&2; exit 1; }

# --- 4. PNG ----------------------------------------------------------------------------
python3 "$root/tools/device/rgb565_to_png.py" "$out/fig6.rgb565" "$out/fig6.png" 160 120
echo "image: $out/fig6.png"
if (( update_png )); then
    cp "$out/fig6.png" "$fw/fig6-qemu.png"
    echo "updated examples/cortex-m4/fig6-qemu.png"
elif ! cmp -s "$out/fig6.png" "$fw/fig6-qemu.png"; then
    echo "note: examples/cortex-m4/fig6-qemu.png differs from this run's image (--update-png to refresh)"
fi

# --- 5. the host renders the same bytes ---------------------------------------------------
step "host render vs device bytes (cargo test --test device)"
(cd "$root" && CAUSTIC_DEVICE_RGB565="$out/fig6.rgb565" CAUSTIC_DEVICE_FNV1A="$fnv" \
    cargo test --test device -- --nocapture --test-threads 1) 2>&1 | tee "$out/host-test.log"
grep -q "bit-identical to the host render" "$out/host-test.log" \
    || { echo "run.sh: the host test did not compare the device's bytes" >&2; exit 1; }

# --- 6. budget and profile ------------------------------------------------------------
step "budget"
"$root/tools/device/budget.sh" "$elf" "$out/qemu.log" "$out/insn-profile.txt" "$out/host-test.log"
step "instruction profile (tools/device/profile.py)"
python3 "$root/tools/device/profile.py" --top 8 "$elf" "$out/insn-profile.txt" | tee "$out/profile.txt"

echo
echo "run.sh: PASS (device and host bit-identical, fnv1a=$fnv) in $(( $(date +%s) - start )) s"
