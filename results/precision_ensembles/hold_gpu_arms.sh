#!/usr/bin/env bash
# Issue 31 under `hold`: the arms still to run on a GPU machine (seed 1 and
# the default scene as 32-run GPU ensembles, and the default scene's CPU f64
# arm on the same machine's cores, at the same time). Run from this folder
# with `slipfront` on PATH (on the lent machine: after ../../shared/device's
# on-gpu.sh has put the packed binaries there), then compare:
#   slipfront compare hold_seed1_cpu_f64.csv hold_seed1_gpu_f32.csv -o hold_seed1_f64_vs_gpu_f32.png
#   slipfront compare hold_default_cpu_f64.csv hold_default_gpu_f32.csv -o hold_default_f64_vs_gpu_f32.png
# About 2 minutes of GPU per ensemble (H200, session 8), and 4 minutes for
# the f64 arm on 16 cores.
set -eu
out=${OUT:-.}
slipfront sweep default_hold.toml --backend cpu --precision f64 --threads 0 -o "$out/default_f64" --quiet &
slipfront sweep precursors_hold_seed1.toml --backend gpu --precision f32 -o "$out/seed1_gpu" --quiet
slipfront sweep default_hold.toml --backend gpu --precision f32 -o "$out/default_gpu" --quiet
wait
cp "$out/seed1_gpu/summary.csv" "$out/hold_seed1_gpu_f32.csv"
cp "$out/default_gpu/summary.csv" "$out/hold_default_gpu_f32.csv"
cp "$out/default_f64/summary.csv" "$out/hold_default_cpu_f64.csv"
