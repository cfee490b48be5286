#!/usr/bin/env bash
# Issue 31 under `hold`: the GPU arms of seed 1 and of the default scene as
# 32-run GPU ensembles in mixed f32 (their CPU f64 and CPU mixed f32 arms
# are here). Run on an H200 on 2026-11-27: the tables are here as
# hold_seed1_gpu_h200_f32.csv and hold_default_gpu_h200_f32.csv (renamed
# after the card), results/precision_ensembles.md section 0a. To run them
# again on another GPU, from this folder with `slipfront` on PATH, then
# compare here:
#   slipfront compare hold_seed1_cpu_f64.csv hold_seed1_gpu_f32.csv -o hold_seed1_f64_vs_gpu_f32.png
#   slipfront compare hold_default_cpu_f64.csv hold_default_gpu_f32.csv -o hold_default_f64_vs_gpu_f32.png
# About 1 minute of GPU per ensemble (H200, 2026-11-27).
set -eu
out=${OUT:-.}
slipfront sweep precursors_hold_seed1.toml --backend gpu --precision f32 -o "$out/seed1_gpu" --quiet
cp "$out/seed1_gpu/summary.csv" "$out/hold_seed1_gpu_f32.csv"
slipfront sweep default_hold.toml --backend gpu --precision f32 -o "$out/default_gpu" --quiet
cp "$out/default_gpu/summary.csv" "$out/hold_default_gpu_f32.csv"
