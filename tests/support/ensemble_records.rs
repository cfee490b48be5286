//! An ensemble's device samples beside each scene's solo run, shared by
//! the ensemble record tests of both precisions.

use slipfront::engines::gpu::ensemble::GpuEnsemble;
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuReal};
use slipfront::engines::{Sample, SamplePlan};
use slipfront::{advance_to, Engine, Model};

/// What one ensemble and the solo runs of its scenes recorded.
pub struct EnsembleRecords {
    /// Each scene's samples from the ensemble.
    pub ensemble: Vec<Vec<Sample>>,
    /// Each scene's samples from its solo run.
    pub solo: Vec<Vec<Sample>>,
    /// The ensemble's output dispatches.
    pub output_dispatches: u64,
}

/// `models` stepped as one ensemble on `opts` by `chunks` of steps, every
/// scene recording at `plan` from the end of the first chunk (`at_first`
/// then gets the ensemble), and each scene alone over the same chunks.
pub fn ensemble_and_solo_records<T: GpuReal>(
    models: &[Model],
    opts: GpuOptions,
    plan: &SamplePlan,
    chunks: &[u64],
    at_first: impl FnOnce(&mut GpuEnsemble<T>),
) -> EnsembleRecords {
    let path = opts.path;
    let mut e = GpuEnsemble::<T>::with_precision(models, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"));
    let mut ensemble = vec![Vec::new(); models.len()];
    let mut at_first = Some(at_first);
    for (i, &n) in chunks.iter().enumerate() {
        e.advance(n).unwrap();
        if i == 0 {
            for k in 0..models.len() {
                assert!(e.record_samples(k, plan).unwrap(), "{path:?}");
            }
            if let Some(f) = at_first.take() {
                f(&mut e);
            }
        }
        for (k, got) in ensemble.iter_mut().enumerate() {
            got.extend(e.take_samples(k));
        }
    }
    let solo = models
        .iter()
        .map(|model| {
            let mut g = GpuEngine::<T>::with_precision(model, opts).unwrap();
            let mut alone = Vec::new();
            for (i, &n) in chunks.iter().enumerate() {
                let target = g.steps_done() + n;
                advance_to(&mut g, target).unwrap();
                if i == 0 {
                    assert!(g.record_samples(plan).unwrap(), "{path:?}");
                }
                alone.extend(g.take_samples());
            }
            alone
        })
        .collect();
    EnsembleRecords {
        ensemble,
        solo,
        output_dispatches: e.output_dispatches(),
    }
}
