//! Section 7: what the junctions cost on Table S1.

use crate::common::{options, path_name, s1_model};
use crate::gpu_timing::solo_step_seconds;
use slipfront::engines::gpu::kernel_choice::candidates;
use slipfront::engines::gpu::shaders::Kernel;
use slipfront::engines::gpu::GpuOptions;
use slipfront::model::scenario::built_in;
use slipfront::{Model, Scenario};

/// What a Table S1 step costs with fewer junction lanes and with none:
/// the same lattice with Ns = 100 (64 lanes per interface block, as
/// shipped) with every junction summed every step and with quiet blocks'
/// sums kept (the default; the timed span is after the normal-load phase,
/// where the precursors scene is quiet), Ns = 16 (16 lanes), Coulomb
/// friction (no junctions) and no friction (the bulk alone), per kernel at
/// its default threads; the
/// shipped scene also with wgpu's run-time checks in the kernels. Where the junctions' share is large, the
/// lane sums (one thread adds a block's lanes, in order) are the step's
/// critical path; where it is small, the stencil and the barriers are.
pub fn cost(min_seconds: f64) {
    // 7. What the junctions cost on Table S1.
    println!("\n## 7. What the junctions cost on Table S1\n");
    println!("What the junctions cost (Table S1 lattice, each kernel at its default threads):\n");
    println!("| friction | kernel | µs/step | host CPU / wall |");
    println!("| --- | --- | ---: | ---: |");
    let text = built_in("tromborg2014_precursors").expect("shipped scene");
    every_junction_summed(text, min_seconds);
    for (name, set) in [
        (
            "junctions, Ns = 100 (64 lanes), quiet blocks' sums kept",
            None,
        ),
        (
            "junctions, Ns = 16 (16 lanes)",
            Some("friction.junctions.count=16"),
        ),
        ("Coulomb (no junctions)", Some("friction.law=coulomb")),
        // No friction at all: the bulk, the update and the step's overhead
        // alone, on every kernel the tiled one included (it refuses
        // Coulomb, a per-block law).
        ("no friction (the bulk alone)", Some("friction.law=none")),
    ] {
        let set: Vec<String> = set.map(String::from).into_iter().collect();
        let scenario = Scenario::parse(text, "table S1", &set).expect("a Table S1 variant");
        let model = Model::from_scenario(&scenario, false).expect("a Table S1 variant");
        kept_rows(name, &model, set.is_empty(), min_seconds);
    }
    println!();
}

/// The shipped scene in `text` on each kernel with every junction summed
/// every step.
fn every_junction_summed(text: &str, min_seconds: f64) {
    // The same scene with every junction summed every step: what keeping a
    // quiet block's sums (`GpuOptions::keep_junction_sums`) saves.
    // And with every lane's sum through storage: what merging runs of
    // lanes in subgroups first saves where every block is summed.
    for kernel in candidates(&s1_model(text, &[])) {
        let shuffles: &[bool] = if kernel.merges_lanes_through_storage() {
            &[true, false]
        } else {
            &[true]
        };
        for &shuffle in shuffles {
            let opts = GpuOptions {
                keep_junction_sums: false,
                lane_shuffle: shuffle,
                ..options(kernel)
            };
            let figure = match solo_step_seconds(&s1_model(text, &[]), opts, min_seconds) {
                Ok((s, host)) => format!("{:.2} | {host:.2}", s * 1e6),
                Err(e) => format!("not run: {e} |"),
            };
            let lanes = match (kernel.merges_lanes_through_storage(), shuffle) {
                (false, _) => "",
                (true, true) => ", lanes merged in subgroups first",
                (true, false) => ", every lane's sum through storage",
            };
            println!(
                "| junctions, Ns = 100, every junction summed every step{lanes} | {} | {figure} |",
                path_name(kernel)
            );
        }
    }
}

/// The rows of scene variant `name` (`model`) with quiet blocks' sums
/// kept, on each kernel; `as_shipped`: the shipped scene, which also
/// gets the variants of `variants`.
fn kept_rows(name: &str, model: &Model, as_shipped: bool, min_seconds: f64) {
    for kernel in candidates(model) {
        let kept = GpuOptions {
            keep_junction_sums: true,
            ..options(kernel)
        };
        for way in variants(kernel, kept, as_shipped) {
            let figure = match solo_step_seconds(model, way, min_seconds) {
                Ok((s, host)) => format!("{:.2} | {host:.2}", s * 1e6),
                Err(e) => format!("not run: {e} |"),
            };
            println!(
                "| {name}{} | {} | {figure} |",
                how(&way, &kept),
                path_name(kernel)
            );
        }
    }
}

/// A row's label after the scene's name: how its options `way` differ
/// from the kernel's as run by default (`base`).
fn how(way: &GpuOptions, base: &GpuOptions) -> &'static str {
    let chained = way.chained_tiles && !base.chained_tiles;
    let sums_anew = !way.published_halo_sums && base.published_halo_sums;
    let device_barriers = !way.workgroup_barriers && base.workgroup_barriers;
    if chained && device_barriers {
        ", rounds chained in one dispatch, phase barriers at device scope (naga's, before session 62)"
    } else if device_barriers {
        ", phase barriers at device scope (naga's, before session 62)"
    } else if chained && sums_anew {
        ", rounds chained in one dispatch, halo sums made anew each round (before session 60)"
    } else if chained {
        ", rounds chained in one dispatch"
    } else if sums_anew {
        ", halo sums made anew each round (before session 60)"
    } else if way.shader_checks != base.shader_checks {
        ", wgpu's run-time checks in the kernels"
    } else if way.bond_patches != base.bond_patches {
        ", bulk forces by 2×2 patches of blocks"
    } else if way.noted_junction_blocks != base.noted_junction_blocks {
        ", each lane and update calling junction_block for its block (before session 33)"
    } else {
        ""
    }
}

/// The options to run `kernel` with on a scene variant: `base` and its
/// edits.
fn variants(kernel: Kernel, base: GpuOptions, as_shipped: bool) -> Vec<GpuOptions> {
    let mut variants = vec![base];
    // The scene as shipped also with wgpu's run-time checks in the
    // kernels (`GpuOptions::shader_checks`): what leaving them out saves;
    // and with their bulk forces by patches of blocks
    // (`GpuOptions::bond_patches`).
    if as_shipped {
        variants.push(GpuOptions {
            shader_checks: true,
            ..base
        });
        variants.push(GpuOptions {
            bond_patches: true,
            ..base
        });
        if matches!(kernel, Kernel::Resident | Kernel::Tiled) {
            variants.push(GpuOptions {
                noted_junction_blocks: false,
                ..base
            });
        }
    }
    // The phase barriers with naga's device scope
    // (`GpuOptions::workgroup_barriers` off), on every scene: what a
    // device-scope barrier costs each phase of a step, where the engine
    // gives them workgroup scope (not on adapters where it writes no
    // SPIR-V of its own: there the two rows are the same module).
    if kernel.has_phase_barriers() {
        variants.push(GpuOptions {
            workgroup_barriers: false,
            ..base
        });
    }
    // The tiled kernel's rounds chained in one dispatch, on every
    // scene (the bulk alone too): what a dispatch a round costs. On the
    // shipped scene also each round's halo sums made anew
    // (`GpuOptions::published_halo_sums`), both ways: what publishing the
    // sums with the junctions saves.
    if kernel == Kernel::Tiled {
        let chained = GpuOptions {
            chained_tiles: true,
            ..base
        };
        variants.push(chained);
        variants.push(GpuOptions {
            workgroup_barriers: false,
            ..chained
        });
        if as_shipped {
            for way in [base, chained] {
                variants.push(GpuOptions {
                    published_halo_sums: false,
                    ..way
                });
            }
        }
    }
    variants
}
