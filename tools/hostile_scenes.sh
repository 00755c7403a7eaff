#!/usr/bin/env bash
# The bar of issue 16 with an optimised program: 150 hostile scenes (tests/support/hostile.rs)
# through the release `caustic` binary; each exits 0 with finite pixels or 2 with a message,
# none panics, each within its deterministic work bound, none over 10 s. Prints the slowest.
# (CI runs the same test in the test profile, opt-level 1.)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release --test hostile -- --nocapture hostile_scenes_through_the_program
