#!/usr/bin/env bash
# The GPU measurements a session lent a GPU should take, in one device call, the most
# decisive first. Each step is cut off at its own cap and at what is left of the call's
# budget, so a short loan still brings back the figures that decide issue 32, and the
# call leaves time to run again.
#
# On the GPU machine, after a release build and packing here:
#   cargo build --release --bins --benches --tests
#   ../shared/device/pack.sh gpu_registers gpu_targets gpu_ensemble gpu_chained_tiles gpu_f64 gpu_table gpu_precision output_writer gpu_host
#   device call, carry [".devbin"]: bash .devbin/on-gpu.sh 'bash ../benches/gpu_call.sh 420'
# (on-gpu.sh runs its command from .devbin/, with the packed binaries on PATH).
#
# Argument: the budget in seconds (default 420: a 600 s call, with room for start-up).
# SLIPFRONT_GPU_CALL_STEPS=targets,bits runs only those steps (names below).
# SLIPFRONT_GPU_CALL_QUICK=1 runs every step in its benches' quick form: a smoke test of
# this script on a software adapter, not a figure.
#
# Each step prints a header with its cap, and a line with its wall time and exit status;
# the summary at the end lists every step as ran, cut off (timeout) or skipped (no time
# left, or not asked for).
set -u
budget=${1:-420}
start=$(date +%s)
quick=${SLIPFRONT_GPU_CALL_QUICK:-}
only=${SLIPFRONT_GPU_CALL_STEPS:-}
summary=()

if [ -n "$quick" ]; then
  export SLIPFRONT_GPU_TARGETS_QUICK=1 SLIPFRONT_GPU_TABLE_QUICK=1 SLIPFRONT_GPU_PRECISION_QUICK=1
fi

# step NAME CAP_SECONDS COMMAND...: runs COMMAND under `timeout`, capped at CAP_SECONDS
# and at the budget left.
step() {
  local name=$1 cap=$2
  shift 2
  if [ -n "$only" ] && [[ ",$only," != *",$name,"* ]]; then
    summary+=("$name: not asked for")
    return
  fi
  local left=$((budget - ($(date +%s) - start)))
  if [ "$left" -lt 20 ]; then
    summary+=("$name: skipped, ${left} s of the budget left")
    return
  fi
  local limit=$((cap < left ? cap : left))
  echo
  echo "=== $name (at most ${limit} s): $*"
  local t0 rc
  t0=$(date +%s)
  timeout --kill-after=10 "$limit" "$@"
  rc=$?
  local took=$(($(date +%s) - t0))
  if [ "$rc" -eq 124 ] || [ "$rc" -eq 137 ]; then
    summary+=("$name: cut off after ${took} s (its cap ${limit} s)")
  else
    summary+=("$name: ${took} s, exit ${rc}")
  fi
  echo "=== $name: ${took} s, exit ${rc}"
}

# A step's own environment goes through `env VAR=VALUE... COMMAND`: `timeout` runs an
# executable, so a shell function there fails with exit 127.

# 0. Where a step's time goes on the device (gpu_table section 11, session 63): each
#    phase's SM cycles a workgroup-step (forces, updates, a tiled round's load,
#    publication and wait on its neighbours), read by thread 0 of each workgroup from
#    the SM's own clock (VK_KHR_shader_clock), for Table S1 alone and 132 scenes, with
#    what the clock reads cost. Which phase holds the 6.84 us of chained tiles and the
#    11 us of resident decides what to build next; first, since a minute of it
#    says more than any other step (the targets' figures stand from session 50).
step phases 60 env SLIPFRONT_GPU_TABLE_SECTIONS=11 gpu_table
# 0'. What the clocks cost the kernels in registers on NVIDIA's compiler (on RADV, navi21:
#     the same VGPRs, no spills): a clocked kernel that spilled would time itself slower.
step registers-clocked 30 env SLIPFRONT_GPU_REGISTERS_PHASE_CLOCKS=1 \
  SLIPFRONT_GPU_REGISTERS_LAUNCHES=persistent/1024,persistent/1024/2-scenes,resident/1024,tiled/512/8x4/chained \
  gpu_registers
# 1. The targets, met or not: auto's pick against every launch timed again, Table S1
#    µs/step, 256 scenes' aggregate and auto's pick there against the persistent and
#    resident launches timed again (session 50's auto timed them 5-6x slow), 64 scenes
#    against one at a time, output cost; in f64 (what a default run computes in on a GPU
#    with f64 shaders) and then in mixed f32.
step targets 310 gpu_targets
# 1'. Strict arithmetic (the default: the engine's own SPIR-V with every floating-point
#     operation NoContraction; mixed f32's fusion guards compiled out, session 67; f64
#     decorated too since session 68, which makes every f64 kernel the CPU reference bit for
#     bit on lavapipe) against wgpu's modules, each launch both ways in one run (gpu_table
#     section 12: mixed f32 launches, the one-step ones included, then three in f64); and
#     NVIDIA's registers for wgpu's build (step 7's are strict's). On AMD's compiler strict
#     issues 2.5-5 % fewer instructions in mixed f32 and 4-7 % more in f64; on NVIDIA it
#     also gives up the fused multiply-adds, so only this says what it costs there.
step arithmetic 150 env SLIPFRONT_GPU_TABLE_SECTIONS=12 gpu_table
step registers-guarded 30 env SLIPFRONT_GPU_REGISTERS_ARITHMETIC=guarded \
  SLIPFRONT_GPU_REGISTERS_LAUNCHES=one-step,one-step-lanes,resident/1024,tiled/512/8x4/chained gpu_registers
# 1''. The phase barriers at workgroup scope (session 62's default, the engine's own SPIR-V)
#     against naga's device scope, each launch both ways in one run (gpu_table section 10):
#     Table S1 alone (persistent, resident, tiled, chained; f32 and f64) and 132 and 264
#     scenes. On AMD's compiler (RADV, navi21) the two compile to the same instructions; what
#     NVIDIA's compiler makes of a device-scope barrier (a fence to L2 each phase of a step?)
#     only this measures.
step barriers 120 env SLIPFRONT_GPU_TABLE_SECTIONS=10 gpu_table
# 1a. The host's CPU a step of each launch, three ways: the default (arrays in arenas, the
#     step as an immediate, session 56), the step by a dynamic offset (session 55), and a
#     buffer per array as well (before 55); and a bare dispatch against the buffers it binds
#     (benches/gpu_host.rs). On the 2-core container, lavapipe, the one-step launches' host
#     CPU a step went 2.9 -> 1.5 -> 1.35 us; session 50's H200 one-step launches were
#     host-bound (the host busy 0.77 of a 5.92 us step).
step host 100 gpu_host 2
# 2. The ensemble target's other launches, at 1 and 256 scenes: resident/512 (two waves of
#    one scene an SM, about 2.04e10 by section 8 on the H200 in session 50, where `auto`
#    mis-timed it), bond patches, and the one-step kernel.
step ensembles 150 env SLIPFRONT_GPU_TABLE_SECTIONS=3 SLIPFRONT_GPU_TABLE_SCENES=1,256 \
  SLIPFRONT_GPU_TABLE_LAUNCHES=resident/512,resident/1024/bond-patches,persistent/1024/bond-patches,one-step,one-step/bond-patches \
  gpu_table
# 2a. Where the output's cost at 1024×512 lies: section 4, each run with the device's busy
#     time and the host's CPU by thread (session 50: 0.445 s for 20,000 steps in f32 and
#     f64 alike, which points at the host or memory traffic, not arithmetic).
step output 120 env SLIPFRONT_GPU_TABLE_SECTIONS=4 gpu_table
# 2a'. The host's side of that output on this machine's CPU, without the GPU: the
#      runner's encoding and the writing thread's zstd, per 1024-column `/interface`
#      message (benches/output_writer.rs; on the 2-core container the writer's zstd took
#      131 µs a slipping row, against the 36 µs a sample the 1.3× target leaves). Seconds.
step output-host 30 output_writer 3000
# 2a''. What NVIDIA's compiler makes of the kernels that step a scene on one SM (resident)
#      and on a few (chained tiles), and of the one-step kernel: its internal
#      representations where the driver gives them (VK_KHR_pipeline_executable_properties),
#      written to $OUT/isa. A Table S1 step on one SM is bound by the instructions the bulk
#      force issues (BENCHMARKS.md, session 52); RADV's disassembly counts them for AMD, this
#      would for the H200: the division's form, the bounds, each loop's length. Seconds.
step isa 40 env SLIPFRONT_GPU_REGISTERS_DUMP="${OUT:-.}/isa" \
  SLIPFRONT_GPU_REGISTERS_LAUNCHES=resident/1024,tiled/512/8x4/chained,one-step-lanes gpu_registers
# 2a'''. Table S1 ≤ 3 µs: chained tiles by width (2-16), halo (1, 2, 4) and threads, with the
#       device's busy time a step (gpu_table section 9). Since session 53 `auto` also times
#       chained widths 2 and 4 at its fastest chained halo on hardware; this step times
#       every shape apart. The nearest launch so far is 8 columns, halo 4, at 6.84 µs
#       (session 50).
step chained-shapes 110 env SLIPFRONT_GPU_TABLE_SECTIONS=9 gpu_table
# 2b. Ensemble against solo, bit for bit (the "the ensemble and solo tests pass").
step bits 90 gpu_ensemble --test-threads 1
# 2c. Chained tiles on hardware: the same bits as a dispatch a round, a scene of 64 tiles
#     at once, and an ensemble of chained scenes against their solo runs (lavapipe can
#     check only one scene at a time).
step chained 60 gpu_chained_tiles --test-threads 1
# 2c'. Strict f64 (`--gpu-arithmetic strict`) against the CPU reference, bit for bit, on
#      every kernel through the stick-slip window (6,000 driving steps, 13,633 ruptures):
#      true on lavapipe since session 68; on NVIDIA only if its f64 division and square
#      roots round as IEEE's. A failure names the first kernel that parts.
step f64-bits 60 env SLIPFRONT_TEST_CPU_BITS=1 gpu_f64 \
  every_f64_kernel_built_strict --test-threads 1
# 2d. auto's pick for a run with an output file (the default job's `-o`), in f64: timed
#     recording Table S1's samples at its cadences, against each launch timed again
#     recording them (output weighs on the launches unequally: BENCHMARKS.md, session 39).
step output-pick 90 env SLIPFRONT_GPU_TARGETS_WITH_OUTPUT=only SLIPFRONT_GPU_TARGETS_PRECISIONS=f64 \
  gpu_targets
# 3. What limits an ensemble: 1 to 528 scenes of resident and persistent at 256 and 1024
#    threads, for Ns = 100, Ns = 16 and Coulomb in mixed f32 and Ns = 100 in f64 (there
#    with one junction lane a round too) (docs/gpu-kernels.md, "What limits an
#    ensemble"): whether scenes that share an SM contend in the bulk phase or in the
#    junction phase, which decides what to build.
step limits 180 env SLIPFRONT_GPU_TABLE_SECTIONS=8 gpu_table
# 4. Table S1 per kernel: kept sums, lane shuffles, run-time checks, bond patches.
step junctions 150 env SLIPFRONT_GPU_TABLE_SECTIONS=7 gpu_table
# 5. Kernels against lattice size (the one-step kernels with and without bond patches),
#    and Table S1's thread counts and tile shapes.
step kernels 200 env SLIPFRONT_GPU_TABLE_SECTIONS=1,2 gpu_table
# 6. Accuracy: the GPU kernels' perturbation ensembles against CPU f64.
step precision 300 gpu_precision

# 7. The registers each kernel's thread holds, as NVIDIA's driver reports them, and the
#    workgroups an SM holds by them: whether Table S1 scenes can share an SM at all. It
#    compiles only, but every launch in two precisions took over 60 s on the H200
#    (session 50, which measured them: BENCHMARKS.md), hence last (benches/gpu_registers.rs).
step registers 60 gpu_registers
# 7b. The tiled kernel's recording variant (TILE_RECORDS: a run with an output file records
#     its samples in the tiled kernel's steps), its registers against step 0's.
step registers-recording 30 env SLIPFRONT_GPU_REGISTERS_SET=TILE_RECORDS=1 \
  SLIPFRONT_GPU_REGISTERS_LAUNCHES=tiled/256/8x4,tiled/1024/16x4,tiled/256/8x4/chained gpu_registers
# 7c. The one-step kernels' recording variant (STEP_RECORDS: the step dispatch of a sample
#     records it; its reduction's 64 slots: step_kernel::step_recording_constants), its
#     registers against step 0's.
step registers-step-recording 30 env SLIPFRONT_GPU_REGISTERS_SET=STEP_RECORDS=1,REDUCTION_WIDTH=64 \
  SLIPFRONT_GPU_REGISTERS_LAUNCHES=one-step,one-step/bond-patches,one-step-lanes gpu_registers
# 7d. The ensemble launches with one junction lane a round (TWO_LANES_A_ROUND=0, a launch
#     `auto` times on hardware): two Table S1 scenes share an SM only at 128 registers or
#     fewer at 256 threads (resident/256 held 139 in session 50). On AMD's compiler (RADV
#     navi21, session 51) the option took f64 resident/256 from 88 VGPRs to 80 and
#     persistent/256 from 88 to 72, and left f32 at 64.
step registers-one-lane 30 env SLIPFRONT_GPU_REGISTERS_SET=TWO_LANES_A_ROUND=0 \
  SLIPFRONT_GPU_REGISTERS_LAUNCHES=resident/256,resident/512,persistent/256 gpu_registers

echo
echo "=== gpu_call summary (budget ${budget} s, used $(($(date +%s) - start)) s)"
for line in "${summary[@]}"; do echo "- $line"; done
