//! The GPU kernel a sweep steps its points with. `auto` on a hardware
//! adapter (and `measure` anywhere) times the kernels on an ensemble of the
//! sweep's own lattice, once per lattice shape (and caches the choice, as a
//! run does): which kernel fills the GPU best depends on how many scenes
//! share it, so the solo choice of `run` would not do. Every point of that
//! shape then runs that kernel, at the threads timed fastest where the
//! single-workgroup kernels were timed at several, alone or in an ensemble
//! alike, so a table does not depend on --ensemble: the ensemble timed is
//! `DEFAULT_ENSEMBLE` scenes (fewer if the sweep has fewer points of the
//! shape, or the adapter holds fewer), whatever --ensemble says. Elsewhere
//! (`auto` on a software adapter, or a kernel named) the rule of
//! `options::choose_kernel` holds.

use super::{Point, SweepOptions, DEFAULT_ENSEMBLE};
use crate::app::runner::sample_plan;
use crate::engines::backend::{Backend, Precision};
use crate::engines::gpu::kernel_choice::{lattice_key, resolve_scenes, ChoiceCache, Launch};
use crate::engines::gpu::options::without_measuring;
use crate::engines::gpu::{context, GpuEngine, GpuOptions, GpuOutput, GpuPath};
use crate::model::Model;

/// The measured kernel of each lattice shape of a sweep.
#[derive(Debug, Default)]
pub struct SweepKernels {
    /// (`lattice_key`, the launch timed fastest) per shape measured: its
    /// kernel, threads, tile shape, lanes and patches.
    chosen: Vec<(String, Launch)>,
    software: bool,
    /// What was measured, a line per shape (for the sweep's log).
    pub report: Vec<String>,
}

impl SweepKernels {
    /// Chooses the kernel of each lattice shape among `points` where the
    /// options ask for a measured choice; none otherwise. A shape whose
    /// candidates all fail to build keeps the rule (its points then say
    /// what fails).
    pub fn choose(points: &[Point], opts: &SweepOptions) -> Result<SweepKernels, String> {
        let gpu_precision = matches!(opts.precision, Precision::F32 | Precision::F64);
        let measured = matches!(opts.gpu.path, GpuPath::Auto | GpuPath::Measure);
        if opts.backend != Backend::Gpu || !gpu_precision || !measured {
            return Ok(SweepKernels::default());
        }
        let ctx = context::shared().map_err(|e| e.to_string())?;
        let mut kernels = SweepKernels {
            software: ctx.is_software(),
            ..SweepKernels::default()
        };
        if opts.gpu.path == GpuPath::Auto && kernels.software {
            return Ok(kernels);
        }
        let models: Vec<(Model, &Point)> = points
            .iter()
            .filter_map(|p| Some((Model::from_scenario(&p.scenario, false).ok()?, p)))
            .collect();
        let cache = ChoiceCache::default_location();
        let mut shapes: Vec<(String, &Model, &Point, usize)> = Vec::new();
        for (m, p) in &models {
            let key = lattice_key(m);
            match shapes.iter_mut().find(|(k, ..)| *k == key) {
                Some(shape) => shape.3 += 1,
                None => shapes.push((key, m, p, 1)),
            }
        }
        for (key, model, point, count) in shapes {
            let scenes = ensemble_limit(model, count.min(DEFAULT_ENSEMBLE), opts.precision);
            // Every point writes its run file: the launches are timed
            // recording the samples of the shape's first point, as its
            // ensemble records them (an ensemble records at one plan).
            let gpu = GpuOptions {
                samples: (opts.gpu.output == GpuOutput::Device)
                    .then(|| sample_plan(model, &point.scenario)),
                ..opts.gpu
            };
            let resolved = match opts.precision {
                Precision::F64 => resolve_scenes::<f64>(model, scenes, &ctx, gpu, &cache),
                _ => resolve_scenes::<f32>(model, scenes, &ctx, gpu, &cache),
            };
            let line = match resolved {
                Ok((_, Some(choice))) => {
                    kernels.chosen.push((key.clone(), choice.launch));
                    choice.describe()
                }
                Ok((_, None)) => continue,
                Err(e) => format!("not measured ({e}): the rule's kernel runs"),
            };
            kernels.report.push(format!("GPU kernel for {key}: {line}"));
        }
        Ok(kernels)
    }

    /// The options a point of `model` runs with, alone or in an ensemble:
    /// its shape's measured launch (the whole launch, as `run` takes it:
    /// a kernel without its measured patches or tile shape would step other
    /// bits than the choice says), else the rule's kernel for `gpu.path`.
    pub fn options(&self, model: &Model, gpu: GpuOptions) -> GpuOptions {
        let key = lattice_key(model);
        match self.chosen.iter().find(|(k, _)| *k == key) {
            Some(&(_, launch)) => launch.options(gpu),
            None => GpuOptions {
                path: without_measuring(gpu.path, self.software),
                ..gpu
            },
        }
    }
}

/// The most scenes like `model` one ensemble takes: `asked` (--ensemble),
/// within what one storage binding of the adapter holds, so that a large
/// lattice makes smaller ensembles rather than failing to build one and
/// running its points one at a time.
pub fn ensemble_limit(model: &Model, asked: usize, precision: Precision) -> usize {
    let Ok(ctx) = context::shared() else {
        return asked;
    };
    let fit = match precision {
        Precision::F64 => GpuEngine::<f64>::scenes_that_fit(model, &ctx.limits),
        _ => GpuEngine::<f32>::scenes_that_fit(model, &ctx.limits),
    };
    asked.min(fit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::gpu::shaders::Kernel;
    use crate::engines::gpu::tiles::TileShape;
    use crate::model::scenario::Scenario;

    /// Every point of a measured shape runs the launch that was timed, the
    /// whole of it: the patches, tile shape and lanes in storage as well
    /// as the kernel and its threads. (Keeping only the kernel and threads
    /// ran `one-step` where `one-step/bond-patches` was chosen, and the
    /// table then differed in the last bits from the named launch's.)
    #[test]
    fn a_measured_shape_runs_the_whole_launch_timed() {
        let model = Model::from_scenario(&Scenario::default_scene(), false).unwrap();
        let shape = TileShape { width: 16, halo: 2 };
        let launches = [
            Launch::of(Kernel::OneStep).with_bond_patches(),
            Launch::with_threads(Kernel::Tiled, 256).with_tile(shape),
            Launch::with_threads(Kernel::Persistent, 512).with_lanes_in_storage(),
            Launch::with_threads(Kernel::Resident, 256).with_one_lane_a_round(),
            Launch::with_threads(Kernel::Resident, 1024).with_lane_run(4),
            Launch::with_threads(Kernel::Tiled, 256)
                .with_tile(shape)
                .with_chained_tiles(),
        ];
        for launch in launches {
            let kernels = SweepKernels {
                chosen: vec![(lattice_key(&model), launch)],
                ..SweepKernels::default()
            };
            let asked = GpuOptions {
                path: GpuPath::Measure,
                ..GpuOptions::default()
            };
            let runs = kernels.options(&model, asked);
            assert_eq!(runs.path, GpuPath::of(launch.kernel), "{}", launch.name());
            assert_eq!(runs.persistent_threads, launch.threads, "{}", launch.name());
            assert_eq!(runs.bond_patches, launch.bond_patches, "{}", launch.name());
            assert_eq!(runs.tile, launch.tile, "{}", launch.name());
            assert_eq!(
                runs.lane_shuffle,
                !launch.lanes_in_storage,
                "{}",
                launch.name()
            );
            assert_eq!(
                runs.two_lanes_a_round,
                !launch.one_lane_a_round,
                "{}",
                launch.name()
            );
            assert_eq!(
                runs.chained_tiles,
                launch.chained_tiles,
                "{}",
                launch.name()
            );
            assert_eq!(
                runs.lane_run,
                launch.lane_run.unwrap_or(1),
                "{}",
                launch.name()
            );
        }
    }
}
