//! Output samples: what one output instant holds, channel by channel, the
//! cadences that make a step an output instant, and `record_sample`, the
//! CPU twin of the GPU code that writes the same records on the device
//! (`shaders/record_common.wgsl`, in the step kernels' steps).

use super::Snapshot;
use crate::engines::step_params::{step_params, Consts};
use crate::model::{Driver, Model};

/// Output samples an engine planned to record on the device, and those of
/// them it computed: the GPU one-step kernels skip the fast cadence's
/// samples that cannot be due (`shaders/record_step.wgsl`, its fast chain).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PlannedAndComputed {
    pub planned: u64,
    pub computed: u64,
}

impl std::fmt::Display for PlannedAndComputed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} planned, {} computed", self.planned, self.computed)
    }
}

/// The output cadences, in steps from the start of driving (0: off), and
/// the slip speed above which the interface switches to the fast cadence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplePlan {
    pub prep_steps: u64,
    pub every_global: u64,
    pub every_interface: u64,
    pub every_bulk: u64,
    pub every_fast: u64,
    pub fast_slip_speed: f64,
    /// The fast cadence is on (decided at the previous sample).
    pub fast: bool,
}

/// What the fixed cadences make due at one step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Due {
    pub global: bool,
    pub interface: bool,
    pub bulk: bool,
    /// A multiple of the fast cadence: due if the fast cadence is on then.
    pub fast: bool,
}

impl Due {
    /// Due whatever the fast cadence is.
    pub fn fixed(self) -> bool {
        self.global || self.interface || self.bulk
    }

    pub fn any(self) -> bool {
        self.fixed() || self.fast
    }
}

fn multiple(d: u64, every: u64) -> bool {
    every > 0 && d.is_multiple_of(every)
}

impl SamplePlan {
    /// The channels the cadences make due at `step` (none before driving).
    pub fn due(&self, step: u64) -> Due {
        if step < self.prep_steps {
            return Due::default();
        }
        let d = step - self.prep_steps;
        Due {
            global: multiple(d, self.every_global),
            interface: multiple(d, self.every_interface),
            bulk: multiple(d, self.every_bulk),
            fast: multiple(d, self.every_fast),
        }
    }
}

/// The sums over the lattice that every sample carries: the global
/// channel's, and what the run's summary, event count and fast cadence need.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SampleSums {
    /// Kinetic energy at the instant (synchronised velocities) (J).
    pub kinetic_energy: f64,
    /// Friction along x, summed over the interface (N).
    pub friction: f64,
    /// Pinned fraction, mean over the interface blocks.
    pub pinned_fraction: f64,
    /// The least pinned fraction of an interface block.
    pub min_pinned_fraction: f64,
    /// The largest |v_x| of an interface block (m/s).
    pub max_slip_speed: f64,
    /// Junction ruptures plus Amontons–Coulomb stick → slip transitions.
    pub ruptures: u64,
    /// u_x of the block the side spring pulls (m); 0 for other drivers.
    pub driven_ux: f64,
    /// The top row's constraint reaction for a prescribed top velocity
    /// (N): Σ m(v_next − v(n−½))/dt − F − friction; 0 for other drivers.
    pub top_reaction: f64,
}

/// The interface channel's fields at one instant, per interface block.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InterfaceRow {
    pub ux: Vec<f64>,
    pub friction: Vec<f64>,
    pub normal: Vec<f64>,
    pub pinned_fraction: Vec<f64>,
    pub slip_speed: Vec<f64>,
}

/// The bulk channel's fields at one instant, per block (f32, as written).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BulkField {
    pub ux: Vec<f32>,
    pub uz: Vec<f32>,
    pub vx: Vec<f32>,
    pub vz: Vec<f32>,
}

/// One output instant: the sums always, the interface row and the bulk
/// field when they are due.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    pub step: u64,
    pub time: f64,
    pub sums: SampleSums,
    pub interface: Option<InterfaceRow>,
    pub bulk: Option<BulkField>,
}

/// The sample of `snap` with the interface row and the bulk field if
/// asked. CPU twin of `block_sample` summed over the blocks and
/// `record_batch_finish` (`shaders/record_common.wgsl`,
/// `shaders/record_batch.wgsl`), which sum in the kernels' precision on
/// the device; these sums are f64.
pub fn record_sample(model: &Model, snap: &Snapshot, interface: bool, bulk: bool) -> Sample {
    let nx = model.nx;
    let pinned = snap.pinned_fraction(nx);
    let top_reaction = match model.driver {
        Driver::TopVelocity { .. } => {
            let v_next = step_params(&Consts::<f64>::new(model), snap.step).top_velocity;
            let top = (model.nz - 1) * nx;
            (top..top + nx)
                .map(|i| {
                    let friction = snap.friction.get(i).copied().unwrap_or(0.0);
                    model.mass * (v_next - snap.vel_half[i][0]) / model.dt
                        - snap.force[i][0]
                        - friction
                })
                .sum()
        }
        _ => 0.0,
    };
    let sums = SampleSums {
        kinetic_energy: snap.kinetic_energy(model.mass),
        friction: snap.total_friction(),
        pinned_fraction: pinned.iter().sum::<f64>() / pinned.len().max(1) as f64,
        min_pinned_fraction: pinned.iter().copied().fold(f64::INFINITY, f64::min),
        max_slip_speed: (0..nx).map(|ix| snap.vel[ix][0].abs()).fold(0.0, f64::max),
        ruptures: snap.total_ruptures(),
        driven_ux: match model.driver {
            Driver::SideSpring { row, .. } => snap.disp[row * nx][0],
            _ => 0.0,
        },
        top_reaction,
    };
    let interface = interface.then(|| InterfaceRow {
        ux: (0..nx).map(|ix| snap.disp[ix][0]).collect(),
        friction: snap.friction.clone(),
        normal: snap.normal.clone(),
        pinned_fraction: pinned.clone(),
        slip_speed: (0..nx).map(|ix| snap.vel[ix][0]).collect(),
    });
    let bulk = bulk.then(|| {
        let col = |f: &dyn Fn(usize) -> f64| (0..snap.disp.len()).map(|i| f(i) as f32).collect();
        BulkField {
            ux: col(&|i| snap.disp[i][0]),
            uz: col(&|i| snap.disp[i][1]),
            vx: col(&|i| snap.vel[i][0]),
            vz: col(&|i| snap.vel[i][1]),
        }
    });
    Sample {
        step: snap.step,
        time: snap.time,
        sums,
        interface,
        bulk,
    }
}
