#!/usr/bin/env python3
"""Instruction counts of the firmware, per phase and per function, from insn_plugin.so.

    profile.py ELF PLUGIN_OUTPUT [--objdump PATH] [--top N] [--summary-only]

The plugin writes, per translated block, its address, its instruction count and the
block's execution count at each `caustic_mark_*` hit and at exit. This script
disassembles the ELF (llvm-objdump -d -l), attributes every executed instruction to the
function symbol that contains it and to its source line (the innermost one: after LTO
most of caustic is inlined into `main`, so the line says more than the symbol), and
prints for each phase (photons: forward pass; render: backward pass, tone map and
semihosted writes) the total and the top functions, source files and lines.

Standard library only: no third-party packages.
"""

import argparse
import collections
import os
import re
import subprocess
import sys

MARKS = [
    "caustic_mark_photons_begin",
    "caustic_mark_photons_end",
    "caustic_mark_render_begin",
    "caustic_mark_render_end",
]


def default_objdump():
    sysroot = subprocess.run(
        ["rustc", "--print", "sysroot"], check=True, capture_output=True, text=True
    ).stdout.strip()
    host = re.search(
        r"^host: (\S+)",
        subprocess.run(["rustc", "-vV"], check=True, capture_output=True, text=True).stdout,
        re.M,
    ).group(1)
    return os.path.join(sysroot, "lib", "rustlib", host, "bin", "llvm-objdump")


def disassemble(objdump, elf):
    """[(addr, function, source)] for every instruction, in address order; marks."""
    out = subprocess.run(
        [objdump, "-d", "-l", "-C", "--no-show-raw-insn", elf],
        check=True, capture_output=True, text=True,
    ).stdout
    insns = []
    marks = {}
    func = "?"
    src = "?"
    head = re.compile(r"^([0-9a-f]+) <(.*)>:$")
    line = re.compile(r"^; (/.*):(\d+)$")
    insn = re.compile(r"^\s+([0-9a-f]+):\s+(.*)$")
    for text in out.splitlines():
        m = head.match(text)
        if m:
            func = re.sub(r"::h[0-9a-f]{16}$", "", m.group(2))
            src = "?"
            if func in MARKS:
                marks[func] = int(m.group(1), 16)
            continue
        m = line.match(text)
        if m:
            src = f"{shorten(m.group(1))}:{m.group(2)}"
            continue
        m = insn.match(text)
        if m:
            body = m.group(2)
            # Literal-pool data shows its raw bytes and a .word/.short/.byte directive.
            if re.match(r"^([0-9a-f]{2} )+\s*\.(word|short|byte|long)", body):
                continue
            insns.append((int(m.group(1), 16), func, src))
    return insns, marks


def shorten(path):
    """A source path without the machine-specific prefix."""
    for pat, rep in (
        (r"^.*/library/", "std:"),
        (r"^.*/registry/src/[^/]+/", ""),
        (r"^.*/examples/device/", "firmware:"),
    ):
        if re.match(pat, path):
            return re.sub(pat, rep, path)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    if path.startswith(root + "/"):
        return path[len(root) + 1:]
    return path


def read_blocks(path):
    with open(path) as f:
        header = f.readline().split()
        assert header[:2] == ["#", "marks"], f"{path}: not an insn_plugin output"
        hits = [int(a, 16) for a in header[2:]]
        blocks = []
        for text in f:
            parts = text.split()
            blocks.append((int(parts[0], 16), int(parts[1]), [int(c) for c in parts[2:]]))
    return hits, blocks


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("elf")
    ap.add_argument("profile")
    ap.add_argument("--objdump", default=None)
    ap.add_argument("--top", type=int, default=12)
    ap.add_argument("--summary-only", action="store_true",
                    help="print only the phase totals, as KEY=VALUE lines")
    args = ap.parse_args()

    insns, marks = disassemble(args.objdump or default_objdump(), args.elf)
    index = {addr: i for i, (addr, _, _) in enumerate(insns)}
    hits, blocks = read_blocks(args.profile)

    missing = [m for m in MARKS if m not in marks]
    if missing:
        sys.exit(f"profile.py: marks not in the ELF: {missing}")
    # Snapshot index of each mark (in the order of the plugin's hits), then "exit".
    order = {}
    for i, addr in enumerate(hits):
        for name, a in marks.items():
            if a == addr and name not in order:
                order[name] = i
    if len(order) != len(MARKS):
        sys.exit(f"profile.py: not every mark was hit (hits at {[hex(h) for h in hits]})")
    phases = {
        "photons": (order[MARKS[0]], order[MARKS[1]]),
        "render": (order[MARKS[2]], order[MARKS[3]]),
        "total": (None, len(hits)),
    }

    results = {}
    for phase, (a, b) in phases.items():
        by_func = collections.Counter()
        by_file = collections.Counter()
        by_line = collections.Counter()
        total = 0
        unknown = 0
        for vaddr, n, counts in blocks:
            runs = counts[b] - (counts[a] if a is not None else 0)
            if runs == 0:
                continue
            total += runs * n
            i = index.get(vaddr)
            if i is None:
                unknown += runs * n
                continue
            for _, func, src in insns[i:i + n]:
                by_func[func] += runs
                by_file[src.rsplit(":", 1)[0]] += runs
                by_line[src] += runs
        results[phase] = (total, unknown, by_func, by_file, by_line)

    if args.summary_only:
        for phase, (total, *_rest) in results.items():
            print(f"insns_{phase}={total}")
        return

    for phase in ("render", "photons", "total"):
        total, unknown, by_func, by_file, by_line = results[phase]
        print(f"== {phase}: {total:,} instructions"
              + (f" ({unknown:,} in blocks outside the disassembly)" if unknown else ""))
        if phase == "total":
            continue
        for title, table in (("function symbol", by_func), ("source file (innermost)", by_file),
                             ("source line (innermost)", by_line)):
            print(f"  by {title}:")
            for key, count in table.most_common(args.top):
                print(f"    {100.0 * count / total:5.1f}%  {count:>12,}  {key}")
        print()


if __name__ == "__main__":
    main()
