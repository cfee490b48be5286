//! The fast CPU engine ("sweep"): the reference engine's arithmetic, bit
//! for bit, in a structure built for the CPU — structure-of-arrays state,
//! each bond computed once (`rows`), and one pass over memory per step that
//! advances a row, then computes the bonds and forces that need it, then
//! the interface row's friction (`chunk`). The state is double-buffered
//! (read step n, write step n + 1), so bands of rows run on several threads
//! with one barrier per step and the same bits as one thread; how many
//! threads a small lattice takes is timed on the scene (`threads`).
//!
//! This engine departs in structure from the WGSL kernels; `CpuEngine` (the
//! kernels' twin) stays the reference, and the tests hold this engine to it
//! bit for bit (`tests/sweep_engine.rs`).

mod chunk;
mod interface;
mod persistent;
mod rows;
mod step;
pub mod threads;

use crate::engines::kernels::bulk_forces::bond_consts;
use crate::engines::step_params::Consts;
use crate::engines::{
    blow_up, Engine, EngineError, EngineState, FrictionState, Snapshot, StateArrays,
};
use crate::model::lattice::{block_flags, initial_displacement};
use crate::model::real::{Coordinate, Real};
use crate::model::{Driver, Model};
pub use chunk::Isa;
use chunk::{Band, Scratch};
use rows::{ForwardBonds, RowView};
use step::{Advance, Fixed, Interface, InterfaceArrays, Shared, StateView};

/// Lattices with at least this many blocks run on every core when the
/// thread count is left to the engine; smaller ones on the count a trial
/// on the run's own steps finds fastest (`threads`). Measured in
/// BENCHMARKS.md ("CPU engine: sweep"; session 69 for the trial).
pub const PARALLEL_MIN_BLOCKS: usize = 4096;

/// Displacements and velocities of a set of blocks, as separate arrays.
#[derive(Debug, Clone)]
pub struct Kinematics<T, C> {
    pub ux: Vec<C>,
    pub uz: Vec<C>,
    pub vx: Vec<T>,
    pub vz: Vec<T>,
}

impl<T: Real, C: Coordinate<T>> Kinematics<T, C> {
    pub fn new(n: usize) -> Self {
        Kinematics {
            ux: vec![C::default(); n],
            uz: vec![C::default(); n],
            vx: vec![T::zero(); n],
            vz: vec![T::zero(); n],
        }
    }

    fn view(&self) -> RowView<'_, T, C> {
        RowView {
            ux: &self.ux,
            uz: &self.uz,
            vx: &self.vx,
            vz: &self.vz,
        }
    }
}

/// One instant: kinematics, bulk forces and the interface's (friction,
/// normal force).
#[derive(Debug, Clone)]
struct State<T, C> {
    kin: Kinematics<T, C>,
    fx: Vec<T>,
    fz: Vec<T>,
    contact: Vec<[T; 2]>,
}

impl<T: Real, C: Coordinate<T>> State<T, C> {
    fn view(&self) -> StateView<'_, T, C> {
        StateView {
            kin: self.kin.view(),
            force: [&self.fx, &self.fz],
            contact: &self.contact,
        }
    }

    fn new(n: usize, nx: usize) -> Self {
        State {
            kin: Kinematics::new(n),
            fx: vec![T::zero(); n],
            fz: vec![T::zero(); n],
            contact: vec![[T::zero(); 2]; nx],
        }
    }
}

/// The sweep engine over one model, in `T` with coordinates `C` (as
/// `CpuEngine`).
pub struct SweepEngine<T: Real, C: Coordinate<T> = <T as Real>::Coord> {
    model: Model,
    fixed: Fixed<T>,
    now: State<T, C>,
    next: State<T, C>,
    friction: FrictionState<T, C>,
    drive_origin: C,
    step: u64,
    /// Row ranges of the bands, bottom (interface) first.
    bands: Vec<std::ops::Range<usize>>,
    scratch: Vec<Scratch<T, C>>,
    pool: Option<rayon::ThreadPool>,
    isa: Isa,
    /// What a trial times at the start of each loading phase (`threads` 0
    /// on a small lattice and a machine of several cores), if anything.
    thread_plan: Option<threads::Plan>,
    /// The trial under way, if any.
    trial: Option<threads::Trial<Option<rayon::ThreadPool>>>,
    /// The last trial's choice and figures.
    threads_timed: Option<threads::Timed>,
    /// Seconds stepped since the last trial ended.
    since_trial: f64,
}

impl<T: Real, C: Coordinate<T>> SweepEngine<T, C> {
    /// `threads`: 1 for one thread, 0 for all cores when the lattice has at
    /// least `PARALLEL_MIN_BLOCKS` blocks (for a smaller one, the count a
    /// trial at the start of each loading phase finds fastest: `threads`);
    /// n > 1 for n bands whatever the size. The results are the same bits
    /// for any count.
    pub fn new(model: &Model, threads: usize) -> Result<Self, EngineError> {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        match threads {
            0 if model.n_blocks() >= PARALLEL_MIN_BLOCKS => Self::build(model, cores, None),
            0 => Self::with_thread_trials(model, threads::Plan::for_machine(model.nz, cores)),
            t => Self::build(model, t, None),
        }
    }

    /// An engine that times `plan`'s thread counts (the first to start
    /// on) at the start of each loading phase and steps the rest of the
    /// phase on the fastest. Fewer than two counts: no trial.
    pub fn with_thread_trials(model: &Model, plan: threads::Plan) -> Result<Self, EngineError> {
        // Each count as the engine can step it (a band a row at most), once.
        let mut counts: Vec<usize> = Vec::new();
        for k in plan.candidates.iter().map(|&k| k.clamp(1, model.nz)) {
            if !counts.contains(&k) {
                counts.push(k);
            }
        }
        let first = counts.first().copied().unwrap_or(1);
        let plan = threads::Plan {
            candidates: counts,
            ..plan
        };
        Self::build(model, first, Some(plan).filter(|p| p.candidates.len() > 1))
    }

    fn build(
        model: &Model,
        threads: usize,
        plan: Option<threads::Plan>,
    ) -> Result<Self, EngineError> {
        let consts = Consts::<T>::new(model);
        let (n, nx, nz) = (model.n_blocks(), model.nx, model.nz);
        let threads = threads.clamp(1, nz);
        let pool = thread_pool(threads)?;
        let bands = band_rows(nz, threads);
        let mut now = State::new(n, nx);
        for (i, u) in initial_displacement(model).into_iter().enumerate() {
            now.kin.ux[i] = C::from_f64(u[0]);
            now.kin.uz[i] = C::from_f64(u[1]);
        }
        let mut engine = SweepEngine {
            fixed: Fixed {
                consts,
                bonds: ForwardBonds::from_stencil(&bond_consts(&consts)),
                flags: block_flags(model),
                law: model.law,
                speed_limit: T::from_f64(model.pressure_wave_speed()),
            },
            next: now.clone(),
            now,
            friction: FrictionState::initial(model),
            drive_origin: C::default(),
            step: 0,
            scratch: bands.iter().map(|_| Scratch::new(nx)).collect(),
            bands,
            pool,
            isa: Isa::detect(),
            model: model.clone(),
            thread_plan: plan,
            trial: None,
            threads_timed: None,
            since_trial: 0.0,
        };
        engine.start_thread_trial()?;
        if model.prep_steps == 0 {
            engine.begin_driving();
        }
        engine.sweep(Advance::Copy, true);
        Ok(engine)
    }

    pub fn threads(&self) -> usize {
        self.bands.len()
    }

    /// The last finished trial's choice of thread count and its figures
    /// (`threads` 0 on a lattice below `PARALLEL_MIN_BLOCKS`, on a machine
    /// with more than one core).
    pub fn threads_timed(&self) -> Option<&threads::Timed> {
        self.threads_timed.as_ref()
    }

    /// Whether a trial of thread counts is under way.
    pub fn timing_threads(&self) -> bool {
        self.trial.is_some()
    }

    /// A new trial of the candidates, from the first (none where there
    /// are fewer than two).
    fn start_thread_trial(&mut self) -> Result<(), EngineError> {
        let Some(plan) = &self.thread_plan else {
            return Ok(());
        };
        let mut trial = threads::Trial::new(plan);
        let first = trial.threads();
        self.switch_threads(&mut trial, first)?;
        self.trial = Some(trial);
        Ok(())
    }

    /// Steps on `threads` threads from now on, setting aside the current
    /// count's bands and pool in `trial` and taking up the new count's
    /// where it has run before. The interface band (the first) keeps its
    /// scratch, which holds the junctions' kept sums.
    fn switch_threads(
        &mut self,
        trial: &mut threads::Trial<Option<rayon::ThreadPool>>,
        threads: usize,
    ) -> Result<(), EngineError> {
        let threads = threads.clamp(1, self.model.nz);
        if threads == self.bands.len() {
            return Ok(());
        }
        let (bands, pool) = match trial.unpark(threads) {
            Some(parked) => parked,
            None => (band_rows(self.model.nz, threads), thread_pool(threads)?),
        };
        let old_bands = std::mem::replace(&mut self.bands, bands);
        let old_pool = std::mem::replace(&mut self.pool, pool);
        trial.park(old_bands.len(), old_bands, old_pool);
        let nx = self.model.nx;
        self.scratch.resize_with(threads, || Scratch::new(nx));
        Ok(())
    }

    /// `advance_bands`, timed where the engine times its thread counts:
    /// during a trial the steps go in the spans it asks for, each on its
    /// count; after one, a new trial starts once the plan's seconds have
    /// been stepped.
    fn advance_timed(&mut self, n: u64) -> Result<Option<usize>, EngineError> {
        let Some(retrial) = self.thread_plan.as_ref().map(|p| p.retrial_seconds) else {
            return Ok(self.advance_bands(n));
        };
        let mut left = n;
        while left > 0 {
            if self.trial.is_none() && self.since_trial >= retrial {
                self.start_thread_trial()?;
            }
            let k = self
                .trial
                .as_ref()
                .map_or(left, |t| t.steps_wanted().min(left));
            let start = std::time::Instant::now();
            let bad = self.advance_bands(k);
            let seconds = start.elapsed().as_secs_f64();
            left -= k;
            match self.trial.take() {
                None => self.since_trial += seconds,
                Some(mut trial) => match trial.record(k, seconds) {
                    threads::Next::Keep => self.trial = Some(trial),
                    threads::Next::Run(threads) => {
                        self.switch_threads(&mut trial, threads)?;
                        self.trial = Some(trial);
                    }
                    threads::Next::Chosen(timed) => {
                        self.switch_threads(&mut trial, timed.threads)?;
                        self.threads_timed = Some(timed);
                        self.since_trial = 0.0;
                    }
                },
            }
            if bad.is_some() {
                return Ok(bad);
            }
        }
        Ok(None)
    }

    /// Interface blocks whose junction sums are kept now (all junctions
    /// pinned since they were made; `junctions::KeptSums`): how much of the
    /// junction pass a quiet step skips.
    pub fn kept_junction_blocks(&self) -> usize {
        self.scratch.iter().map(Scratch::kept_junction_blocks).sum()
    }

    /// An evaluator of forces on one thread, as `CpuEngine::with_junctions`
    /// (the same bits): `base`'s junction arrays and sliding state, for
    /// driving-phase states given by `set_kinematics`, read by `snapshot`.
    /// The quasi-static path's output samples are made with it.
    pub fn with_junctions(
        model: &Model,
        base: &Snapshot,
        drive_origin: f64,
    ) -> Result<Self, EngineError> {
        let mut e = Self::new(model, 1)?;
        e.drive_origin = C::from_f64(drive_origin);
        e.friction.load_junctions(base);
        e.friction.load_slide(base);
        e.forget_junction_sums();
        e.step = model.prep_steps.max(base.step);
        Ok(e)
    }

    /// The instruction set of the band sweep (detected at construction).
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// Runs on the baseline instruction set instead of the detected one:
    /// for the tests that hold both to the reference's bits.
    pub fn use_baseline_isa(&mut self) {
        self.isa = Isa::Baseline;
    }

    /// One pass over all bands into `next` on the calling thread, then
    /// `next` becomes `now`. Returns the index of the first block that blew
    /// up.
    fn sweep(&mut self, advance: Advance, forces: bool) -> Option<usize> {
        let shared = Shared::new(
            &self.fixed,
            self.drive_origin,
            self.step,
            self.now.view(),
            advance,
            forces,
        );
        let isa = self.isa;
        let bands = split_bands(
            &self.bands,
            self.fixed.consts.nx,
            &mut self.next,
            (
                &mut self.friction.junction_spring,
                &mut self.friction.junction_state,
                &mut self.friction.slide,
                &mut self.friction.law_state,
            ),
        );
        let bad = bands
            .into_iter()
            .zip(self.scratch.iter_mut())
            .filter_map(|(band, scratch)| chunk::sweep_band(isa, &shared, band, scratch))
            .min();
        std::mem::swap(&mut self.now, &mut self.next);
        bad
    }

    /// Up to `n` leapfrog steps within one loading phase, each band on its
    /// own thread of the pool with one barrier per step; stops after the
    /// step where a block blew up, and returns that block.
    fn advance_bands(&mut self, n: u64) -> Option<usize> {
        let Some(pool) = &self.pool else {
            for _ in 0..n {
                let bad = self.sweep(Advance::Leapfrog, true);
                self.step += 1;
                if bad.is_some() {
                    return bad;
                }
            }
            return None;
        };
        let run = persistent::Run {
            fixed: &self.fixed,
            drive_origin: self.drive_origin,
            first_step: self.step,
            steps: n,
            bands: &self.bands,
            isa: self.isa,
        };
        let interface = (
            &mut self.friction.junction_spring[..],
            &mut self.friction.junction_state[..],
            &mut self.friction.slide[..],
            &mut self.friction.law_state[..],
        );
        let (done, bad, busy) = run.go(
            pool,
            [&mut self.now, &mut self.next],
            &mut self.scratch,
            interface,
        );
        // Calls of a few steps measure little but noise.
        if done >= 16 {
            self.bands = persistent::rebalance(&self.bands, &busy);
        }
        // Odd step counts leave the newest state in `next`.
        if done % 2 == 1 {
            std::mem::swap(&mut self.now, &mut self.next);
        }
        self.step += done;
        bad
    }

    /// `n` leapfrog steps, each ending with the forces, friction and
    /// junction states of its new state (as `CpuEngine::one_step`); the
    /// step where driving starts runs on its own, with the driver origin
    /// and trigger set between its leapfrog and its forces.
    fn steps(&mut self, n: u64) -> Result<(), EngineError> {
        let end = self.step + n;
        let prep = self.model.prep_steps;
        while self.step < end {
            if self.step + 1 == prep {
                let bad = self.sweep(Advance::Leapfrog, false);
                self.step += 1;
                self.stop_if_blown_up(bad)?;
                self.begin_driving();
                self.sweep(Advance::Copy, true);
                // Driving's work is not the normal load's: timed anew.
                self.start_thread_trial()?;
                continue;
            }
            // Up to the state before that step, or to the end.
            let until = if self.step + 1 < prep { prep - 1 } else { end };
            let bad = self.advance_timed(until.min(end) - self.step)?;
            self.stop_if_blown_up(bad)?;
        }
        Ok(())
    }

    /// The blow-up error for block `bad` of the current state, if any.
    fn stop_if_blown_up(&self, bad: Option<usize>) -> Result<(), EngineError> {
        let Some(i) = bad else { return Ok(()) };
        let k = &self.now.kin;
        let u = [k.ux[i].as_f64(), k.uz[i].as_f64()];
        let v = [k.vx[i].as_f64(), k.vz[i].as_f64()];
        Err(blow_up(&self.model, self.step, i, u, v))
    }

    /// As `CpuEngine::begin_driving`: the driver origin and the trigger's
    /// junction forces, from the displacements where driving starts.
    fn begin_driving(&mut self) {
        if let Driver::SideSpring { row, .. } = self.model.driver {
            self.drive_origin = self.now.kin.ux[row * self.model.nx];
        }
        if self.model.sets_anchors_at_drive_start() {
            let snap = self.snapshot_now();
            let anchors = crate::engines::trigger::trigger_anchors(&self.model, &snap);
            self.friction.set_anchors(anchors);
            self.forget_junction_sums();
        }
    }

    /// Every band's kept junction sums dropped (only the interface band
    /// keeps any): called wherever junctions change other than by stepping.
    fn forget_junction_sums(&mut self) {
        for scratch in &mut self.scratch {
            scratch.forget_junction_sums();
        }
    }

    /// The current state in the reference engine's array-of-pairs layout:
    /// (displacements, velocities, forces).
    #[allow(clippy::type_complexity)]
    fn paired(&self) -> (Vec<[C; 2]>, Vec<[T; 2]>, Vec<[T; 2]>) {
        let k = &self.now.kin;
        let pair = |a: &[T], b: &[T]| a.iter().zip(b).map(|(x, z)| [*x, *z]).collect();
        (
            k.ux.iter().zip(&k.uz).map(|(x, z)| [*x, *z]).collect(),
            pair(&k.vx, &k.vz),
            pair(&self.now.fx, &self.now.fz),
        )
    }

    fn snapshot_now(&self) -> Snapshot {
        let (disp, vel, force) = self.paired();
        Snapshot::from_buffers(
            &self.model,
            self.step,
            &disp,
            &vel,
            &force,
            &self.now.contact,
            &self.friction,
        )
    }
}

/// The pool that steps `threads` bands (none for one: the calling thread
/// steps it).
fn thread_pool(threads: usize) -> Result<Option<rayon::ThreadPool>, EngineError> {
    if threads < 2 {
        return Ok(None);
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map(Some)
        .map_err(|e| EngineError::Gpu(format!("thread pool: {e}")))
}

/// `threads` bands of consecutive rows, as even as the rows allow.
fn band_rows(nz: usize, threads: usize) -> Vec<std::ops::Range<usize>> {
    let threads = threads.clamp(1, nz.max(1));
    (0..threads)
        .map(|t| t * nz / threads..(t + 1) * nz / threads)
        .collect()
}

/// Splits the next state into the bands' rows; the first band (row 0) gets
/// the interface arrays.
fn split_bands<'a, T: Real, C: Coordinate<T>>(
    bands: &[std::ops::Range<usize>],
    nx: usize,
    next: &'a mut State<T, C>,
    arrays: InterfaceArrays<'a, T, C>,
) -> Vec<Band<'a, T, C>> {
    let State {
        kin,
        fx,
        fz,
        contact,
    } = next;
    let (mut ux, mut uz) = (&mut kin.ux[..], &mut kin.uz[..]);
    let (mut vx, mut vz) = (&mut kin.vx[..], &mut kin.vz[..]);
    let (mut fx, mut fz) = (&mut fx[..], &mut fz[..]);
    let mut interface = Some(Interface::new(contact, arrays));
    let mut out = Vec::with_capacity(bands.len());
    for rows in bands {
        let len = rows.len() * nx;
        let (a, rest) = std::mem::take(&mut ux).split_at_mut(len);
        ux = rest;
        let (b, rest) = std::mem::take(&mut uz).split_at_mut(len);
        uz = rest;
        let (c, rest) = std::mem::take(&mut vx).split_at_mut(len);
        vx = rest;
        let (d, rest) = std::mem::take(&mut vz).split_at_mut(len);
        vz = rest;
        let (e, rest) = std::mem::take(&mut fx).split_at_mut(len);
        fx = rest;
        let (f, rest) = std::mem::take(&mut fz).split_at_mut(len);
        fz = rest;
        out.push(Band {
            rows: rows.clone(),
            ux: a,
            uz: b,
            vx: c,
            vz: d,
            fx: e,
            fz: f,
            interface: interface.take(),
        });
    }
    out
}

impl<T: Real, C: Coordinate<T>> Engine for SweepEngine<T, C> {
    fn model(&self) -> &Model {
        &self.model
    }

    fn steps_done(&self) -> u64 {
        self.step
    }

    fn advance(&mut self, n: u64) -> Result<(), EngineError> {
        self.steps(n)
    }

    fn snapshot(&mut self) -> Result<Snapshot, EngineError> {
        Ok(self.snapshot_now())
    }

    fn set_kinematics(
        &mut self,
        step: u64,
        disp: &[[f64; 2]],
        vel: &[[f64; 2]],
    ) -> Result<(), EngineError> {
        crate::engines::assert_driving_phase(&self.model, self.step, step);
        let k = &mut self.now.kin;
        for (i, (u, v)) in disp.iter().zip(vel).enumerate() {
            k.ux[i] = C::from_f64(u[0]);
            k.uz[i] = C::from_f64(u[1]);
            k.vx[i] = T::from_f64(v[0]);
            k.vz[i] = T::from_f64(v[1]);
        }
        self.step = step;
        self.sweep(Advance::Copy, true);
        Ok(())
    }

    fn set_junctions(&mut self, snap: &Snapshot) -> Result<(), EngineError> {
        self.friction.load_junctions(snap);
        self.forget_junction_sums();
        Ok(())
    }

    fn save_state(&mut self) -> Result<EngineState, EngineError> {
        let (disp, vel, force) = self.paired();
        Ok(EngineState::capture(StateArrays {
            step: self.step,
            drive_origin: self.drive_origin,
            disp: &disp,
            vel: &vel,
            force: &force,
            contact: &self.now.contact,
            friction: &self.friction,
        }))
    }

    fn load_state(&mut self, state: &EngineState) -> Result<(), EngineError> {
        state.check_fits(&self.model)?;
        self.step = state.step;
        self.drive_origin = state.drive_origin_as();
        let now = &mut self.now;
        for (i, u) in state.disp_as::<T, C>().into_iter().enumerate() {
            [now.kin.ux[i], now.kin.uz[i]] = u;
        }
        for (i, v) in state.vel_as::<T>().into_iter().enumerate() {
            [now.kin.vx[i], now.kin.vz[i]] = v;
        }
        for (i, f) in state.force_as::<T>().into_iter().enumerate() {
            [now.fx[i], now.fz[i]] = f;
        }
        now.contact = state.contact_as();
        self.friction = FrictionState::from_state(state);
        self.forget_junction_sums();
        Ok(())
    }

    fn describe(&self) -> String {
        format!(
            "cpu {} ({} thread(s), sweep{}){}",
            crate::model::real::precision_name::<T, C>(),
            self.threads(),
            match (&self.trial, &self.threads_timed) {
                (Some(_), _) => format!(
                    "; timing {:?} threads on its steps",
                    self.thread_plan
                        .as_ref()
                        .map_or(&[][..], |p| &p.candidates[..])
                ),
                (None, Some(t)) => format!("; threads timed: {}", t.describe()),
                (None, None) => String::new(),
            },
            crate::engines::precision_probe::label(self.fixed.consts.f32_probe)
        )
    }
}
