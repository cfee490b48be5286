#!/bin/bash
# The junction-parameter sweep of results/junction_sweep.md: each run is the
# Table S1 side-driven scene with some junction parameters changed, in f32 on
# the CPU, with coarser output (interface every 1e-4 s, 1e-5 s while slipping);
# `slipfront info` then lists its events and precursors.
# usage: results/junction_sweep.sh [out_dir]   (two runs at a time)
set -euo pipefail
out=${1:-sweep}
mkdir -p "$out"
bin=${SLIPFRONT:-target/release/slipfront}
[ -x "$bin" ] || cargo build --release
C=friction.junctions.stiffness_coefficient
N=friction.junctions.count
T=friction.junctions.slip_time_mean
S=friction.junctions.slip_time_std
# name  driven time (s)  overrides
jobs=(
  "c3.92e10_t2 0.6"
  "c3.92e10_t1 0.6 $T=1e-3 $S=1e-4"
  "c3.92e10_t0.7 0.6 $T=7e-4 $S=7e-5"
  "c3.92e10_t0.5 0.6 $T=5e-4 $S=5e-5"
  "c3.92e10_t0.5_seed2 0.6 $T=5e-4 $S=5e-5 time.seed=2"
  "c3.92e10_t0.5_seed3 0.6 $T=5e-4 $S=5e-5 time.seed=3"
  "c3.92e10_t0.5_seed4 0.6 $T=5e-4 $S=5e-5 time.seed=4"
  "c3.92e10_t0.5_wide 0.6 $T=5e-4 $S=2.5e-4"
  "c3.92e10_t0.4 0.6 $T=4e-4 $S=4e-5"
  "c3.92e10_t0.3 0.6 $T=3e-4 $S=3e-5"
  "c3.92e10_t0.3_seed2 0.6 $T=3e-4 $S=3e-5 time.seed=2"
  "c3.92e10_t0.3_seed3 0.6 $T=3e-4 $S=3e-5 time.seed=3"
  "c3.92e10_t0.3_seed4 0.6 $T=3e-4 $S=3e-5 time.seed=4"
  "c3.92e10_t0.2 0.6 $T=2e-4 $S=2e-5"
  "c3.92e12_t0.5 0.6 $C=3.92e12 $T=5e-4 $S=5e-5"
  "c3.92e11_t0.5 0.6 $C=3.92e11 $T=5e-4 $S=5e-5"
  "c3.92e11_t0.2 0.6 $C=3.92e11 $T=2e-4 $S=2e-5"
  "c3.92e11_t2 0.6 $C=3.92e11"
  "c1.24e10_t0.5 0.6 $C=1.24e10 $T=5e-4 $S=5e-5"
  "c3.92e9_t2 0.7 $C=3.92e9"
  "c3.92e9_t0.5 0.7 $C=3.92e9 $T=5e-4 $S=5e-5"
  "c3.92e8_t8 0.7 $C=3.92e8 $T=8e-3 $S=8e-4"
  "c3.92e8_t2 0.7 $C=3.92e8"
  "c3.92e8_t0.5 0.7 $C=3.92e8 $T=5e-4 $S=5e-5"
  "c3.92e8_t0.2 0.8 $C=3.92e8 $T=2e-4 $S=2e-5"
  "c3.92e8_t0.1 0.8 $C=3.92e8 $T=1e-4 $S=1e-5"
  "c3.92e7_t0.5 0.8 $C=3.92e7 $T=5e-4 $S=5e-5"
  "Ns1_c3.92e12_t2 0.8 $N=1 $C=3.92e12"
)
one() {
  local name=$1 tend=$2
  shift 2
  local sets=()
  for kv in "$@"; do sets+=(--set "$kv"); done
  "$bin" run scenarios/tromborg2014_stick_slip.toml --backend cpu --precision f32 --threads 1 \
    --quiet --t-end "$tend" --set output.fast_interval=1e-5 --set output.interface_interval=1e-4 \
    --set output.bulk_interval=1 "${sets[@]}" -o "$out/$name.mcap" > "$out/$name.log"
  "$bin" info "$out/$name.mcap" > "$out/$name.info"
}
export -f one
export bin out
printf '%s\n' "${jobs[@]}" | xargs -P 2 -L 1 bash -c 'one $0 "$@"'
