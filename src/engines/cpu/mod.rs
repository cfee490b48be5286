//! The CPU reference engine, in f64 or in mixed f32 (mirroring the GPU's
//! arithmetic: f32 forces, double-single displacements), or in plain f32
//! (the negative control of the precision tests). Each phase is a twin of a
//! WGSL kernel in `shaders/`, with the same name and buffer layout.

pub mod fast;

pub use crate::model::junction::{JunctionSpring, PINNED};
pub use fast::SweepEngine;

use crate::engines::kernels::bulk_forces::{bond_consts, Blocks, BondConsts};
use crate::engines::kernels::junctions::JunctionSlots;
use crate::engines::kernels::{block_laws, bulk_forces, junctions, verlet};
use crate::engines::step_params::{drive_target, step_params, Consts};
use crate::engines::{
    blow_up, Engine, EngineError, EngineState, FrictionState, Snapshot, StateArrays,
};
use crate::model::lattice::{block_flags, initial_displacement};
use crate::model::real::{precision_name, Coordinate, Real};
use crate::model::scenario::FrictionLaw;
use crate::model::{Driver, Model};
use rayon::prelude::*;

/// Lattices smaller than this run single-threaded: below it the fork-join
/// cost per phase exceeds the work.
const PARALLEL_MIN_BLOCKS: usize = 4096;

/// The CPU engine over one model, computing in `T` with displacements,
/// anchors and the drive position accumulated as `C` (by default f64 for
/// f64, double-single for f32).
pub struct CpuEngine<T: Real, C: Coordinate<T> = <T as Real>::Coord> {
    model: Model,
    consts: Consts<T>,
    bonds: [BondConsts<T>; 8],
    speed_limit: T,
    flags: Vec<u32>,
    disp: Vec<[C; 2]>,
    vel: Vec<[T; 2]>,
    force: Vec<[T; 2]>,
    /// (friction along x, normal force) per interface block.
    contact: Vec<[T; 2]>,
    /// The friction laws' junction and sliding arrays.
    friction: FrictionState<T, C>,
    drive_origin: C,
    step: u64,
    pool: Option<rayon::ThreadPool>,
}

impl<T: Real, C: Coordinate<T>> CpuEngine<T, C> {
    /// `threads`: 1 for the deterministic single-thread mode, 0 for all
    /// cores. Results are identical either way (no cross-block reductions).
    pub fn new(model: &Model, threads: usize) -> Result<Self, EngineError> {
        let consts = Consts::<T>::new(model);
        let n = model.n_blocks();
        let threads = if threads == 0 {
            std::thread::available_parallelism().map_or(1, |n| n.get())
        } else {
            threads
        };
        let pool = if threads > 1 && n >= PARALLEL_MIN_BLOCKS {
            Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .map_err(|e| EngineError::Gpu(format!("thread pool: {e}")))?,
            )
        } else {
            None
        };
        let disp = initial_displacement(model)
            .into_iter()
            .map(|u| [C::from_f64(u[0]), C::from_f64(u[1])])
            .collect();
        let mut engine = CpuEngine {
            consts,
            bonds: bond_consts(&consts),
            speed_limit: T::from_f64(model.pressure_wave_speed()),
            flags: block_flags(model),
            disp,
            vel: vec![[T::zero(); 2]; n],
            force: vec![[T::zero(); 2]; n],
            contact: vec![[T::zero(); 2]; model.nx],
            friction: FrictionState::initial(model),
            drive_origin: C::default(),
            step: 0,
            pool,
            model: model.clone(),
        };
        if model.prep_steps == 0 {
            engine.begin_driving();
        }
        engine.force_pass();
        Ok(engine)
    }

    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or(1, |p| p.current_num_threads())
    }

    /// Bulk forces and friction at the current state and step. Run at the
    /// end of every step (and once at the start), so that forces, contact
    /// and junction states always describe the same instant as the
    /// displacements.
    fn force_pass(&mut self) {
        let c = &self.consts;
        let p = step_params(c, self.step);
        let nx = c.nx;
        let blocks = Blocks {
            disp: &self.disp,
            vel: &self.vel,
            flags: &self.flags,
        };
        let bonds = &self.bonds;
        let target = drive_target(c, self.drive_origin, self.step);
        let rows_per_task = (PARALLEL_MIN_BLOCKS / 4 / nx).max(1);
        match &self.pool {
            Some(pool) => pool.install(|| {
                self.force
                    .par_chunks_mut(nx * rows_per_task)
                    .enumerate()
                    .for_each(|(t, chunk)| {
                        let first = t * nx * rows_per_task;
                        bulk_forces::bulk_forces(c, bonds, &p, target, blocks, chunk, first)
                    })
            }),
            None => bulk_forces::bulk_forces(c, bonds, &p, target, blocks, &mut self.force, 0),
        }

        match self.model.law {
            FrictionLaw::None => {}
            law if law.is_per_block() => {
                let words = law.declaration().block_state_words;
                for ix in 0..nx {
                    self.contact[ix] = block_laws::block_law(
                        c,
                        &p,
                        law,
                        self.disp[ix][1],
                        self.vel[ix][0],
                        self.force[ix][0],
                        &mut self.friction.slide[ix],
                        &mut self.friction.law_state[ix * words..(ix + 1) * words],
                    );
                }
            }
            FrictionLaw::Junctions | FrictionLaw::SingleJunction => {
                let ns = c.junction_count;
                let (disp, vel, force) = (&self.disp, &self.vel, &self.force);
                let run = |ix: usize,
                           out: &mut [T; 2],
                           spring: &mut [JunctionSpring<C, T>],
                           state: &mut [[u32; 2]]| {
                    let slots = JunctionSlots { spring, state };
                    let (f, p_n) =
                        junctions::junctions(c, &p, ix, disp[ix], vel[ix], force[ix][0], slots);
                    *out = [f, p_n];
                };
                match &self.pool {
                    Some(pool) => pool.install(|| {
                        self.contact
                            .par_iter_mut()
                            .zip(self.friction.junction_spring.par_chunks_mut(ns))
                            .zip(self.friction.junction_state.par_chunks_mut(ns))
                            .enumerate()
                            .for_each(|(ix, ((out, spring), state))| run(ix, out, spring, state))
                    }),
                    None => {
                        for (ix, ((out, spring), state)) in self
                            .contact
                            .iter_mut()
                            .zip(self.friction.junction_spring.chunks_mut(ns))
                            .zip(self.friction.junction_state.chunks_mut(ns))
                            .enumerate()
                        {
                            run(ix, out, spring, state);
                        }
                    }
                }
            }
            // Every law is per-block or a junction law (`model::friction::Law`).
            law => unreachable!("{law:?} has no engine path"),
        }
    }

    /// One leapfrog step from the forces at the current state, then the
    /// forces at the new one. Twin of the `one_step` and
    /// `persistent_steps` kernels (which compute the forces at the start of
    /// a step instead, the same sequence of operations).
    fn one_step(&mut self) -> Result<(), EngineError> {
        let c = &self.consts;
        let p = step_params(c, self.step);
        let nx = c.nx;
        let rows_per_task = (PARALLEL_MIN_BLOCKS / 4 / nx).max(1);
        let has_friction = self.model.law != FrictionLaw::None;
        let (force, contact, flags) = (&self.force, &self.contact, &self.flags);
        let limit = self.speed_limit;
        let update = |i: usize, u: &mut [C; 2], v: &mut [T; 2]| {
            let fr = if has_friction && i < nx {
                contact[i][0]
            } else {
                T::zero()
            };
            verlet::verlet(c, &p, flags[i], force[i], fr, u, v, limit)
        };
        let bad = match &self.pool {
            Some(pool) => pool.install(|| {
                self.disp
                    .par_iter_mut()
                    .zip(self.vel.par_iter_mut())
                    .enumerate()
                    .with_min_len(nx * rows_per_task)
                    .filter_map(|(i, (u, v))| (!update(i, u, v)).then_some(i))
                    .min()
            }),
            None => {
                let mut bad = None;
                for (i, (u, v)) in self.disp.iter_mut().zip(self.vel.iter_mut()).enumerate() {
                    if !update(i, u, v) && bad.is_none() {
                        bad = Some(i);
                    }
                }
                bad
            }
        };
        self.step += 1;
        if let Some(i) = bad {
            let u = self.disp[i].map(C::as_f64);
            let v = self.vel[i].map(Real::as_f64);
            return Err(blow_up(&self.model, self.step, i, u, v));
        }
        if self.step == self.model.prep_steps {
            self.begin_driving();
        }
        self.force_pass();
        Ok(())
    }

    /// Once, when driving starts (before the forces of that step): fixes
    /// the driver origin and applies the trigger's initial junction forces.
    fn begin_driving(&mut self) {
        if let Driver::SideSpring { row, .. } = self.model.driver {
            self.drive_origin = self.disp[row * self.model.nx][0];
        }
        if self.model.sets_anchors_at_drive_start() {
            let snap = self.snapshot_now();
            let anchors = crate::engines::trigger::trigger_anchors(&self.model, &snap);
            self.friction.set_anchors(anchors);
        }
    }

    /// An engine holding `base`'s junction and slide arrays, for
    /// evaluating the full state (forces, friction, normal forces) of
    /// driving-phase states with `set_kinematics` and `snapshot`: how the
    /// quasi-static path's output samples are made, in this engine's
    /// arithmetic.
    pub fn with_junctions(
        model: &Model,
        base: &Snapshot,
        drive_origin: f64,
    ) -> Result<Self, EngineError> {
        let mut e = Self::new(model, 1)?;
        e.drive_origin = C::from_f64(drive_origin);
        e.friction.load_junctions(base);
        e.friction.load_slide(base);
        e.step = model.prep_steps.max(base.step);
        Ok(e)
    }

    fn snapshot_now(&self) -> Snapshot {
        Snapshot::from_buffers(
            &self.model,
            self.step,
            &self.disp,
            &self.vel,
            &self.force,
            &self.contact,
            &self.friction,
        )
    }
}

impl<T: Real, C: Coordinate<T>> Engine for CpuEngine<T, C> {
    fn model(&self) -> &Model {
        &self.model
    }

    fn steps_done(&self) -> u64 {
        self.step
    }

    fn advance(&mut self, n: u64) -> Result<(), EngineError> {
        for _ in 0..n {
            self.one_step()?;
        }
        Ok(())
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
        for (d, u) in self.disp.iter_mut().zip(disp) {
            *d = [C::from_f64(u[0]), C::from_f64(u[1])];
        }
        for (d, v) in self.vel.iter_mut().zip(vel) {
            *d = [T::from_f64(v[0]), T::from_f64(v[1])];
        }
        self.step = step;
        self.force_pass();
        Ok(())
    }

    fn set_junctions(&mut self, snap: &Snapshot) -> Result<(), EngineError> {
        self.friction.load_junctions(snap);
        Ok(())
    }

    fn save_state(&mut self) -> Result<EngineState, EngineError> {
        Ok(EngineState::capture(StateArrays {
            step: self.step,
            drive_origin: self.drive_origin,
            disp: &self.disp,
            vel: &self.vel,
            force: &self.force,
            contact: &self.contact,
            friction: &self.friction,
        }))
    }

    fn load_state(&mut self, state: &EngineState) -> Result<(), EngineError> {
        state.check_fits(&self.model)?;
        self.step = state.step;
        self.drive_origin = state.drive_origin_as();
        self.disp = state.disp_as();
        self.vel = state.vel_as();
        self.force = state.force_as();
        self.contact = state.contact_as();
        self.friction = FrictionState::from_state(state);
        Ok(())
    }

    fn describe(&self) -> String {
        format!(
            "cpu-reference {} ({} thread(s)){}",
            precision_name::<T, C>(),
            self.threads(),
            crate::engines::precision_probe::label(self.consts.f32_probe)
        )
    }
}
