//! The measured choices of this machine, kept between runs, and the keys
//! they are kept under.

use super::{ChoiceSource, KernelChoice, Launch, TimedPhase};
use crate::engines::gpu::context::GpuContext;
use crate::engines::gpu::options::GpuOptions;
use crate::engines::gpu::precision::GpuReal;
use crate::engines::gpu::shaders::{Kernel, LaneMerge, Variant};
use crate::engines::SamplePlan;
use crate::model::Model;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

/// The cache file in the cache directory.
pub const CACHE_FILE: &str = "gpu-kernels.tsv";

/// The measured choices of this machine, one line per adapter and lattice:
/// `key <TAB> launch <TAB> launch=seconds,... <TAB> phase <TAB> output`
/// (a launch: `resident`, or `resident/512` with its threads; the phase
/// as `TimedPhase::describe` writes it; the output `no output` or
/// `recorded N`, `KernelChoice::recorded`). A line without its phase or
/// its output (an older build's) is measured again.
#[derive(Debug, Clone)]
pub struct ChoiceCache {
    /// None: no cache directory could be found (nothing is kept).
    dir: Option<PathBuf>,
}

impl ChoiceCache {
    /// `$SLIPFRONT_CACHE_DIR`, else `$XDG_CACHE_HOME/slipfront`, else
    /// `~/.cache/slipfront`.
    pub fn default_location() -> ChoiceCache {
        let env = |k: &str| {
            std::env::var_os(k)
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
        };
        let dir = env("SLIPFRONT_CACHE_DIR")
            .or_else(|| env("XDG_CACHE_HOME").map(|d| d.join("slipfront")))
            .or_else(|| env("HOME").map(|d| d.join(".cache").join("slipfront")));
        ChoiceCache { dir }
    }

    pub fn at(dir: &Path) -> ChoiceCache {
        ChoiceCache {
            dir: Some(dir.to_path_buf()),
        }
    }

    pub fn file(&self) -> Option<PathBuf> {
        self.file_named(CACHE_FILE)
    }

    fn file_named(&self, name: &str) -> Option<PathBuf> {
        self.dir.as_ref().map(|d| d.join(name))
    }

    fn lines_of(&self, name: &str) -> Vec<String> {
        self.file_named(name)
            .and_then(|f| std::fs::read_to_string(f).ok())
            .map(|text| text.lines().map(str::to_string).collect())
            .unwrap_or_default()
    }

    /// The fields after `key` on its line of the cache file `name` (a file
    /// of this directory: `key <TAB> fields`), if one is stored.
    pub fn lookup_line(&self, name: &str, key: &str) -> Option<String> {
        self.lines_of(name).into_iter().find_map(|line| {
            let (k, fields) = line.split_once('\t')?;
            (k == key).then(|| fields.to_string())
        })
    }

    /// Stores `fields` under `key` in the cache file `name`, replacing an
    /// older line. The file is written whole and renamed into place, so a
    /// reader never sees half of it. Failing to write only loses the
    /// cache: returns why.
    pub fn store_line(&self, name: &str, key: &str, fields: &str) -> Result<(), String> {
        let (Some(dir), Some(file)) = (&self.dir, self.file_named(name)) else {
            return Err("no cache directory (set SLIPFRONT_CACHE_DIR)".into());
        };
        let mut lines: Vec<String> = self
            .lines_of(name)
            .into_iter()
            .filter(|l| l.split('\t').next() != Some(key))
            .collect();
        lines.push(format!("{key}\t{fields}"));
        let write = || -> std::io::Result<()> {
            std::fs::create_dir_all(dir)?;
            let tmp = dir.join(format!("{name}.{}.tmp", std::process::id()));
            std::fs::write(&tmp, lines.join("\n") + "\n")?;
            std::fs::rename(&tmp, &file)
        };
        write().map_err(|e| format!("cannot write {}: {e}", file.display()))
    }

    /// The choice stored under `key`; a line that does not parse is
    /// ignored (measured again).
    pub fn lookup(&self, key: &str) -> Option<KernelChoice> {
        self.lookup_line(CACHE_FILE, key).and_then(|line| {
            let mut fields = line.split('\t');
            let launch = Launch::named(fields.next()?)?;
            let timings = fields
                .next()?
                .split(',')
                .map(|pair| {
                    let (name, seconds) = pair.split_once('=')?;
                    let seconds: f64 = seconds.parse().ok()?;
                    (seconds.is_finite() && seconds > 0.0)
                        .then_some((Launch::named(name)?, seconds))
                })
                .collect::<Option<Vec<_>>>()?;
            let phase = TimedPhase::described(fields.next()?)?;
            let recorded = recorded_named(fields.next()?)?;
            timings
                .iter()
                .any(|(l, _)| *l == launch)
                .then_some(KernelChoice {
                    launch,
                    timings,
                    source: ChoiceSource::Cached,
                    skipped: Vec::new(),
                    scenes: 1,
                    phase,
                    recorded,
                })
        })
    }

    /// Stores `choice` under `key`, replacing an older line. The file is
    /// written whole and renamed into place, so a reader never sees half
    /// of it. Failing to write only loses the cache: returns why.
    pub fn store(&self, key: &str, choice: &KernelChoice) -> Result<(), String> {
        let figures: Vec<String> = choice
            .timings
            .iter()
            .map(|(l, s)| format!("{}={s:e}", l.name()))
            .collect();
        let fields = format!(
            "{}\t{}\t{}\t{}",
            choice.launch.name(),
            figures.join(","),
            choice.phase.describe().replace(['\t', '\n'], " "),
            recorded_name(choice.recorded)
        );
        self.store_line(CACHE_FILE, key, &fields)
    }
}

/// The cache's output field: `no output`, or `recorded N`.
fn recorded_name(recorded: Option<u64>) -> String {
    recorded.map_or_else(|| NO_OUTPUT.to_string(), |n| format!("{RECORDED}{n}"))
}

/// The inverse of `recorded_name` (None: not one).
fn recorded_named(text: &str) -> Option<Option<u64>> {
    if text == NO_OUTPUT {
        return Some(None);
    }
    text.strip_prefix(RECORDED)?.parse().ok().map(Some)
}

const NO_OUTPUT: &str = "no output";
const RECORDED: &str = "recorded ";

/// The output cadences a choice was timed at, in its key: `none`, or
/// `every 45/90/45000/4 steps` (global, interface, bulk and fast cadences
/// from the start of driving; 0: off).
fn samples_key(samples: Option<&SamplePlan>) -> String {
    samples.map_or_else(
        || "none".to_string(),
        |p| {
            format!(
                "every {}/{}/{}/{} steps",
                p.every_global, p.every_interface, p.every_bulk, p.every_fast
            )
        },
    )
}

/// What a measured choice depends on: the adapter and its driver, the
/// precision, the lattice (`lattice_key`), the persistent kernels' threads,
/// the tile shape where one is fixed, whether the lanes' merge was
/// searched, wgpu's run-time checks, whether the bond patches, the
/// junction lanes a round, lane runs and chained tiles were searched, the
/// phase barriers' scope, how a step was
/// timed (`timing::TIMING`), the output cadences it was timed recording
/// at (`GpuOptions::samples`), and the kernels' sources (a new version
/// of slipfront measures again).
pub fn cache_key<T: GpuReal>(model: &Model, ctx: &GpuContext, opts: GpuOptions) -> String {
    scenes_cache_key::<T>(model, 1, ctx, opts)
}

/// The lattice a choice is for: its shape, junction count and compiled
/// terms (scenes alike in these step at the same speed).
pub fn lattice_key(model: &Model) -> String {
    format!(
        "{}x{} | junctions {} | {}",
        model.nx,
        model.nz,
        model.n_junctions(),
        Variant::for_model(model).describe()
    )
}

/// `cache_key` of an ensemble of `scenes` scenes like `model` (one scene:
/// the solo key).
pub fn scenes_cache_key<T: GpuReal>(
    model: &Model,
    scenes: usize,
    ctx: &GpuContext,
    opts: GpuOptions,
) -> String {
    let mut sources = std::collections::hash_map::DefaultHasher::new();
    for kernel in Kernel::ALL {
        for lanes in [LaneMerge::Storage, LaneMerge::Shuffle] {
            kernel.source_with::<T>(lanes).hash(&mut sources);
        }
    }
    let info = &ctx.info;
    let ensemble = if scenes > 1 {
        format!(" | ensemble of {scenes}")
    } else {
        String::new()
    };
    format!(
        "{} | {:?} | {} {} | {} | {}{ensemble} | threads {} | tiles {} | lanes {} | checks {} | patches {} | lane rounds {} | lane runs {} | chained tiles {} | scenes a workgroup {} | arrays {} | step {} | phase barriers {} | arithmetic {} | timed by {} | samples {} | kernels {:016x}",
        info.name,
        info.backend,
        info.driver,
        info.driver_info,
        T::NAME,
        lattice_key(model),
        opts.persistent_threads
            .map_or_else(|| "default".to_string(), |t| t.to_string()),
        // A choice that searched the tile shape is not one for a fixed shape.
        opts.tile
            .map_or_else(|| "searched".to_string(), |s| s.name()),
        // Nor is one that searched where the lanes merge one for lanes
        // fixed in storage.
        if opts.lane_shuffle {
            "searched"
        } else {
            "in storage"
        },
        // Kernels timed with wgpu's run-time checks ran other code
        // (choices cached before there was a choice were timed with them).
        if opts.shader_checks {
            "wgpu's"
        } else {
            "none"
        },
        // Nor is one that searched the bulk forces' patches one with them
        // fixed on.
        if opts.bond_patches {
            "on"
        } else {
            "searched"
        },
        // Nor one that searched the junction lanes a round one with one
        // lane a round fixed.
        if opts.two_lanes_a_round {
            "searched"
        } else {
            "one"
        },
        // Nor one that searched lane runs one with a run fixed.
        if opts.lane_run == 1 {
            "searched".to_string()
        } else {
            opts.lane_run.to_string()
        },
        // Nor one that searched chained tiles one with them fixed on.
        if opts.chained_tiles {
            "on"
        } else {
            "searched"
        },
        // Nor one that searched scenes a persistent workgroup one with
        // them fixed.
        if opts.group_scenes == 1 {
            "searched".to_string()
        } else {
            opts.group_scenes.to_string()
        },
        // The host's cost of a dispatch grows with the buffers it binds
        // (`GpuOptions::pack_arrays`): choices timed with a buffer per
        // array (all before session 55) favoured launches of few dispatches.
        if opts.pack_arrays {
            "in arenas"
        } else {
            "a buffer each"
        },
        // Nor by the step offset's way to a dispatch
        // (`GpuOptions::step_immediates`).
        if opts.step_immediates {
            "immediate"
        } else {
            "dynamic offset"
        },
        // Nor by the phase barriers' scope (`GpuOptions::workgroup_barriers`).
        if opts.workgroup_barriers {
            "workgroup"
        } else {
            "device"
        },
        // Nor by how the arithmetic is compiled (`GpuOptions::arithmetic`).
        opts.arithmetic.name(),
        // Choices timed by a span's mean step (before session 38) carry
        // each advance's fixed costs: measured again.
        super::timing::TIMING,
        // Output weighs on the launches unequally (`GpuOptions::samples`).
        samples_key(opts.samples.as_ref()),
        sources.finish()
    )
    .replace(['\t', '\n'], " ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The output field reads back as written; anything else is not one
    /// (the line is measured again).
    #[test]
    fn the_output_field_reads_back() {
        for recorded in [None, Some(0), Some(12)] {
            assert_eq!(recorded_named(&recorded_name(recorded)), Some(recorded));
        }
        for damaged in ["", "recorded", "recorded -1", "recorded some", "no outputs"] {
            assert_eq!(recorded_named(damaged), None, "{damaged}");
        }
    }

    /// Choices timed at other cadences, or without output, are kept apart.
    #[test]
    fn the_cadences_are_in_the_key() {
        let plan = SamplePlan {
            prep_steps: 100,
            every_global: 45,
            every_interface: 90,
            every_bulk: 45_000,
            every_fast: 4,
            fast_slip_speed: 1e-3,
            fast: false,
        };
        assert_eq!(samples_key(Some(&plan)), "every 45/90/45000/4 steps");
        assert_eq!(samples_key(None), "none");
        let faster = SamplePlan {
            every_fast: 5,
            ..plan
        };
        assert_ne!(samples_key(Some(&faster)), samples_key(Some(&plan)));
    }
}
