#!/usr/bin/env bash
# Regenerates calib/identify-reduced/ (docs/identify.md, "Multi-DOF reduced models", at full size):
# the synthetic sweeps of the blade–damper example with known factors (seeded noise, so the
# same files every time) and the reduced-model update fitted on the 3 N and 30 N levels,
# predicting 10 N. About 20–30 min on 2 cores (one evaluation of two 36-row sweeps takes
# several seconds with 220 elements). Run from the repository root.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo run --release --example blade_damper_sweeps -- calib/identify-reduced/sweeps
cargo run --release -- identify --structure calib/response/model.toml \
    calib/identify-reduced/sweeps/level{1,2,3}.csv --fit-levels 1,3 --starts 0 \
    --out-dir calib/identify-reduced
# model.json names the response model by absolute path (predict checks it): machine-specific,
# not committed.
rm -f calib/identify-reduced/model.json
