//! The model, defined once: parameters and derived quantities in SI units,
//! used by every engine (CPU and GPU).

pub use crate::model::friction::junctions::JunctionModel;
use crate::model::scenario::{
    Component, DampingForm, DriveMode, EdgeConstraint, FrictionLaw, JunctionStiffness, Scenario,
};

/// What drives the slider tangentially, resolved from the scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Driver {
    None,
    /// Spring of `stiffness` (N/m) on block (0, `row`), pulled at `velocity`.
    SideSpring {
        stiffness: f64,
        row: usize,
        velocity: f64,
    },
    /// Top-row tangential force growing at `rate` (N/s, total over the row).
    TopForce {
        rate: f64,
    },
    /// Top row moved at `velocity` (m/s).
    TopVelocity {
        velocity: f64,
    },
}

/// The initial trigger of a prestressed interface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriggerModel {
    pub shear_prestress: f64,
    pub force_width: f64,
    /// Interface blocks with index below this are in the trigger strip.
    pub strip_blocks: usize,
    pub strip_prestress: f64,
}

/// A uniform shear prestress applied as a tangential force on the
/// interface blocks from the start of driving (`[loading.prestress]`),
/// as ratios τ/p: column ix carries ratio·F_N·share(ix).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrestressModel {
    /// τ/p = μd + τ̄ (μs − μd) on every block outside the trigger.
    pub ratio: f64,
    /// Interface blocks with index below this carry `strip_ratio`.
    pub strip_blocks: usize,
    pub strip_ratio: f64,
}

/// Gaussian initial displacement pulse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PulseModel {
    pub component: Component,
    pub center: f64,
    pub width: f64,
    pub amplitude: f64,
}

/// The model: everything an engine needs, in SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    pub name: String,
    pub nx: usize,
    pub nz: usize,
    /// Lattice spacing l (m).
    pub spacing: f64,
    /// Out-of-plane width B (m).
    pub width: f64,
    /// Block mass m (kg).
    pub mass: f64,
    /// Nearest-neighbour spring stiffness k = 3BE/4 (N/m).
    pub k: f64,
    /// Diagonal spring stiffness k/2 (N/m).
    pub k_diag: f64,
    /// Dashpot coefficient η (kg/s), on every spring.
    pub eta: f64,
    pub damping_form: DampingForm,
    /// Foundation stiffness k_f (N/m).
    pub k_foundation: f64,
    /// T = 2π√(m/k) (s).
    pub period: f64,
    /// Time step (s).
    pub dt: f64,
    pub law: FrictionLaw,
    pub mu_s: f64,
    pub mu_d: f64,
    /// The laws' own tables (`[friction.<law>]`).
    pub law_tables: crate::model::friction::LawTables,
    pub junctions: Option<JunctionModel>,
    /// Total normal load F_N (N).
    pub normal_force: f64,
    /// Slope of the linear normal-load profile, (r − 1)/(r + 1) for the
    /// trailing-to-leading ratio r (0: uniform).
    pub normal_slope: f64,
    pub ramp_steps: u64,
    /// Steps of the whole normal-load phase (ramp and relaxation).
    pub prep_steps: u64,
    /// Absolute-velocity damping (kg/s) during the relaxation.
    pub relax_eta: f64,
    /// Absolute-velocity damping (kg/s) once driving starts.
    pub absolute_eta: f64,
    pub driver: Driver,
    pub trigger: Option<TriggerModel>,
    pub prestress: Option<PrestressModel>,
    pub top: EdgeConstraint,
    pub bottom: EdgeConstraint,
    pub pulse: Option<PulseModel>,
    /// x displacement of every block and junction anchor at t = 0 (m).
    pub start_position: f64,
    /// Steps after the normal-load phase.
    pub drive_steps: u64,
    pub seed: u32,
    pub youngs_modulus: f64,
    pub density: f64,
}

/// The stability limits of the leapfrog step (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilityLimit {
    /// Bulk lattice without damping: 2/ω_max, ω_max = √(6k/m).
    pub bulk_undamped: f64,
    /// Bulk with its dashpots: 2(√(1+ζ²) − ζ)/ω_max.
    pub bulk: f64,
    /// Interface block with foundation and pinned junctions, damped.
    pub interface: f64,
    /// Relaxation phase (extra absolute damping).
    pub relaxation: f64,
    /// The block the side spring pulls (its stiffness on top of the
    /// lattice's, and the interface's when it is in row 0); infinite
    /// without a side spring.
    pub driven: f64,
}

impl StabilityLimit {
    /// The binding limit.
    pub fn min(&self) -> f64 {
        self.bulk
            .min(self.interface)
            .min(self.relaxation)
            .min(self.driven)
    }
}

/// An error in the derived model (the scenario parsed, but the numbers do not work).
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error(
        "time step dt = {dt:.4e} s is above the stability limit {limit:.4e} s ({which}); \
         use time.dt <= {limit:.4e} s (time.dt_fraction <= {fraction:.4}) or pass \
         --allow-unstable to override"
    )]
    Unstable {
        dt: f64,
        limit: f64,
        fraction: f64,
        which: &'static str,
    },
    #[error("{0}")]
    Invalid(String),
}

impl Model {
    /// Derives the model; refuses a time step above the stability limit
    /// unless `allow_unstable`.
    pub fn from_scenario(s: &Scenario, allow_unstable: bool) -> Result<Model, ModelError> {
        let g = &s.geometry;
        let nx = g.nx as usize;
        let nz = g.nz as usize;
        let spacing = if nx > 1 {
            g.length / (nx - 1) as f64
        } else if nz > 1 {
            g.height / (nz - 1) as f64
        } else {
            g.length
        };
        // A single row or column is one spacing thick: its length (height)
        // must say so, or the block mass would come from a size the
        // lattice does not have.
        for (count, size, name, other) in [
            (nx, g.length, "geometry.length", "nx"),
            (nz, g.height, "geometry.height", "nz"),
        ] {
            if count == 1 && (nx > 1 || nz > 1) && (size - spacing).abs() > 1e-9 * spacing {
                return Err(ModelError::Invalid(format!(
                    "{name} = {size} m with {other} = 1: a single row or column of blocks is one \
                     spacing thick (allowed: {name} = {spacing} m, the spacing of the other \
                     direction)"
                )));
            }
        }
        let total_mass = s.material.density * g.length * g.height * g.width;
        let mass = total_mass / (nx * nz) as f64;
        let k = 0.75 * g.width * s.material.youngs_modulus;
        let eta = s.damping.ratio * (k * mass).sqrt();
        let period = 2.0 * std::f64::consts::PI * (mass / k).sqrt();
        let dt = match (s.time.dt, s.time.dt_fraction) {
            (Some(dt), _) => dt,
            (None, Some(f)) => f * period,
            (None, None) => return Err(ModelError::Invalid("no time step".into())),
        };
        // Each input is in range on its own; their products can still leave
        // f64 (geometry.width = 1e308 gives an infinite k and mass, so a
        // NaN period and dt).
        for (name, value, from) in [
            ("lattice spacing", spacing, "geometry.length / (nx − 1)"),
            (
                "block mass",
                mass,
                "material.density × length × height × width / (nx·nz)",
            ),
            (
                "spring stiffness k",
                k,
                "0.75 × geometry.width × material.youngs_modulus",
            ),
            ("oscillation period", period, "2π √(m/k)"),
            (
                "time step dt",
                dt,
                "time.dt, or time.dt_fraction × the period",
            ),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ModelError::Invalid(format!(
                    "derived {name} = {value:e} (from {from}) is not a finite positive number: \
                     the inputs are too large or too small together"
                )));
            }
        }
        if !(eta.is_finite() && eta >= 0.0) {
            return Err(ModelError::Invalid(format!(
                "derived damping coefficient η = {eta:e} (damping.ratio × √(k m)) is not finite"
            )));
        }
        // Step counts exact in f64 (and far from u64's end): a longer time
        // would wrap the step count (time.end = 1e300 was a 13 409-step run).
        for (name, t) in [
            ("time.end", s.time.end),
            ("loading.normal.ramp_time", s.loading.normal.ramp_time),
            ("loading.normal.relax_time", s.loading.normal.relax_time),
        ] {
            if t / dt >= 2f64.powi(53) {
                // Name what set dt: a tiny dt is more often a material out
                // of scale (youngs_modulus = 1e308) than a long run.
                let dt_from = match s.time.dt {
                    Some(_) => "time.dt".to_string(),
                    None => format!(
                        "time.dt_fraction × the period 2π√(m/k) = {period:.4e} s, set by \
                         material.density = {:e} and material.youngs_modulus = {:e}",
                        s.material.density, s.material.youngs_modulus
                    ),
                };
                return Err(ModelError::Invalid(format!(
                    "{name} = {t:e} s is out of range (allowed: below {:.4e} s, 2^53 steps of dt \
                     = {dt:.4e} s, so that every step time is exact); dt comes from {dt_from}",
                    2f64.powi(53) * dt
                )));
            }
        }
        let steps = |t: f64| (t / dt).round() as u64;
        let ramp_steps = steps(s.loading.normal.ramp_time);
        let prep_steps = ramp_steps + steps(s.loading.normal.relax_time);
        let junctions = match s.friction.law {
            FrictionLaw::Junctions | FrictionLaw::SingleJunction => {
                let j = s.friction.junctions.as_ref().ok_or_else(|| {
                    ModelError::Invalid("missing table [friction.junctions]".into())
                })?;
                Some(JunctionModel::from_table(j, k))
            }
            _ => None,
        };
        let d = &s.loading.drive;
        let driver = match d.mode {
            DriveMode::None => Driver::None,
            DriveMode::SideSpring => Driver::SideSpring {
                stiffness: d.stiffness.unwrap_or(0.0),
                row: ((d.height.unwrap_or(0.0) / spacing).round() as usize).min(nz - 1),
                velocity: d.velocity.unwrap_or(0.0),
            },
            DriveMode::TopForce => Driver::TopForce {
                rate: d.force_rate.unwrap_or(0.0),
            },
            DriveMode::TopVelocity => Driver::TopVelocity {
                velocity: d.velocity.unwrap_or(0.0),
            },
        };
        let trigger = s.loading.trigger.as_ref().map(|t| TriggerModel {
            shear_prestress: t.shear_prestress,
            force_width: t.force_width,
            strip_blocks: ((t.strip_length / spacing).round() as usize + 1).min(nx),
            strip_prestress: t.strip_prestress,
        });
        let (mu_s, mu_d) = (
            s.friction.static_coefficient,
            s.friction.dynamic_coefficient,
        );
        let prestress = s.loading.prestress.as_ref().map(|p| PrestressModel {
            ratio: mu_d + p.tau_bar * (mu_s - mu_d),
            strip_blocks: (p.trigger_blocks as usize).min(nx),
            strip_ratio: mu_d + p.trigger_tau_bar * (mu_s - mu_d),
        });
        let model = Model {
            name: s.name.clone(),
            nx,
            nz,
            spacing,
            width: g.width,
            mass,
            k,
            k_diag: 0.5 * k,
            eta,
            damping_form: s.damping.form,
            k_foundation: s.foundation.stiffness_ratio * k,
            period,
            dt,
            law: s.friction.law,
            mu_s: s.friction.static_coefficient,
            mu_d: s.friction.dynamic_coefficient,
            law_tables: s.friction.law_tables(),
            junctions,
            normal_force: s.loading.normal.force,
            normal_slope: {
                let r = s.loading.normal.trailing_to_leading;
                (r - 1.0) / (r + 1.0)
            },
            ramp_steps,
            prep_steps,
            relax_eta: s.loading.normal.relax_damping_ratio * 2.0 * (k * mass).sqrt(),
            absolute_eta: s.damping.absolute_ratio * (k * mass).sqrt(),
            driver,
            trigger,
            prestress,
            top: s.boundary.top,
            bottom: s.boundary.bottom,
            pulse: s.pulse.as_ref().map(|p| PulseModel {
                component: p.component,
                center: p.center,
                width: p.width,
                amplitude: p.amplitude,
            }),
            start_position: s.start.as_ref().map_or(0.0, |st| st.position),
            drive_steps: steps(s.time.end),
            seed: s.time.seed,
            youngs_modulus: s.material.youngs_modulus,
            density: s.material.density,
        };
        // A drive faster than the lattice's P wave cannot be represented:
        // the engines flag any block that fast as a blow-up.
        let drive_speed = match model.driver {
            Driver::SideSpring { velocity, .. } | Driver::TopVelocity { velocity } => velocity,
            _ => 0.0,
        };
        let c_p = model.pressure_wave_speed();
        if drive_speed.abs() >= c_p {
            return Err(ModelError::Invalid(format!(
                "loading.drive.velocity = {drive_speed} m/s is out of range (allowed: below \
                 the lattice P-wave speed, |V| < {} m/s)",
                if c_p >= 0.1 {
                    format!("{c_p:.1}")
                } else {
                    format!("{c_p:.4e}")
                }
            )));
        }
        // What the run can represent: a slip time within the 32-bit slip
        // countdown, and step times exact in f64.
        if let Some(j) = model.junctions {
            let longest = (j.slip_time_mean + 10.0 * j.slip_time_std) / model.dt;
            if longest >= (u32::MAX - 1) as f64 {
                return Err(ModelError::Invalid(format!(
                    "friction.junctions.slip_time_mean + 10 slip_time_std = {:.4e} s is out of \
                     range (allowed: below {:.4e} s, 2^32 - 2 steps of dt = {:.4e} s)",
                    j.slip_time_mean + 10.0 * j.slip_time_std,
                    (u32::MAX - 1) as f64 * model.dt,
                    model.dt
                )));
            }
        }
        if s.time.end > 0.0 && model.drive_steps == 0 {
            return Err(ModelError::Invalid(format!(
                "time.end = {:e} s is shorter than one time step dt = {:.4e} s: the run would \
                 end before it starts (allowed: time.end >= dt/2)",
                s.time.end, model.dt
            )));
        }
        if model.total_steps() as f64 >= 2f64.powi(53) {
            return Err(ModelError::Invalid(format!(
                "time.end = {} s is out of range (allowed: below {:.4e} s, 2^53 steps of dt = \
                 {:.4e} s, so that every step time is exact)",
                s.time.end,
                2f64.powi(53) * model.dt,
                model.dt
            )));
        }
        if !allow_unstable {
            let lim = model.stability_limit();
            let (limit, which) = [
                (lim.bulk, "bulk lattice with damping"),
                (
                    lim.interface,
                    "interface block with foundation and junctions",
                ),
                (lim.relaxation, "normal-load relaxation damping"),
                (lim.driven, "the block the side spring pulls"),
            ]
            .into_iter()
            .fold((f64::INFINITY, ""), |a, b| if b.0 < a.0 { b } else { a });
            if dt > limit {
                return Err(ModelError::Unstable {
                    dt,
                    limit,
                    fraction: limit / period,
                    which,
                });
            }
        }
        Ok(model)
    }

    pub fn n_blocks(&self) -> usize {
        self.nx * self.nz
    }

    /// Total junction slots (interface blocks × Ns); 0 without junctions.
    pub fn n_junctions(&self) -> usize {
        self.junctions.map_or(0, |j| j.count * self.nx)
    }

    /// The friction law's constants, in the engines' run constants as
    /// `law` (`crate::model::friction::constants`).
    pub fn law_constants(&self) -> [f64; crate::model::friction::LAW_CONSTANTS] {
        crate::model::friction::constants(self.law, self.mu_s, self.mu_d, &self.law_tables)
    }

    /// The friction law's state of each interface block at t = 0
    /// (`block_state_words` values).
    pub fn law_initial_state(&self) -> Vec<f64> {
        crate::model::friction::initial_block_state(self.law, &self.law_tables)
    }

    pub fn total_steps(&self) -> u64 {
        self.prep_steps + self.drive_steps
    }

    /// Time (s) of global step `step`; zero when driving starts.
    pub fn time_of_step(&self, step: u64) -> f64 {
        (step as f64 - self.prep_steps as f64) * self.dt
    }

    /// Top-row share of a total force: edge blocks take half shares.
    pub fn top_share(&self, ix: usize) -> f64 {
        crate::model::laws::top_share(self.nx, self.nz, ix)
    }

    /// Share of the normal load F_N that top column `ix` carries (the top
    /// share times the normal-load profile).
    pub fn normal_share(&self, ix: usize) -> f64 {
        self.top_share(ix) * crate::model::laws::normal_profile(self.normal_slope, self.nx, ix)
    }

    /// Lattice long-wave shear speed c_s = l√(k/(2m)).
    pub fn shear_wave_speed(&self) -> f64 {
        self.spacing * (self.k / (2.0 * self.mass)).sqrt()
    }

    /// Lattice long-wave P speed c_p = l√(3k/(2m)).
    pub fn pressure_wave_speed(&self) -> f64 {
        self.spacing * (1.5 * self.k / self.mass).sqrt()
    }

    /// Rayleigh speed from the Rayleigh equation with the lattice c_p/c_s.
    pub fn rayleigh_wave_speed(&self) -> f64 {
        let cs = self.shear_wave_speed();
        let r2 = (cs / self.pressure_wave_speed()).powi(2);
        // (2 − ξ²)² − 4√(1 − ξ²)√(1 − r²ξ²) changes sign once on (0, 1).
        let f = |xi: f64| {
            let x2 = xi * xi;
            (2.0 - x2).powi(2) - 4.0 * (1.0 - x2).sqrt() * (1.0 - r2 * x2).sqrt()
        };
        let (mut lo, mut hi) = (0.5, 0.999_999);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if f(lo) * f(mid) <= 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        0.5 * (lo + hi) * cs
    }

    /// Tangential force (N) the prestress applies to interface column `ix`
    /// once driving starts: ratio × F_N × the column's share (0 without
    /// `[loading.prestress]`).
    pub fn interface_shear(&self, ix: usize) -> f64 {
        self.prestress.map_or(0.0, |p| {
            let ratio = if ix < p.strip_blocks {
                p.strip_ratio
            } else {
                p.ratio
            };
            ratio * self.normal_force * self.normal_share(ix)
        })
    }

    /// True when the junctions' anchors are set when driving starts (a
    /// trigger, or a prestress carried by junctions).
    pub fn sets_anchors_at_drive_start(&self) -> bool {
        self.junctions.is_some() && (self.trigger.is_some() || self.prestress.is_some())
    }

    /// Young's modulus of the lattice, 4k/(3B).
    pub fn lattice_youngs_modulus(&self) -> f64 {
        4.0 * self.k / (3.0 * self.width)
    }

    /// Per-junction normal force at mean load, with a factor 2 margin for the
    /// stress concentration at the edges (used by the stability estimate).
    fn junction_normal_force_bound(&self) -> f64 {
        let ns = self.junctions.map_or(1, |j| j.count) as f64;
        let per_block =
            self.normal_force * self.top_share(self.nx / 2) * (1.0 + self.normal_slope.abs());
        2.0 * per_block / ns
    }

    /// Largest junction stiffness the run is expected to see (N/m).
    pub fn junction_stiffness_bound(&self) -> f64 {
        match self.junctions {
            None => 0.0,
            Some(j) => match j.stiffness {
                JunctionStiffness::Constant | JunctionStiffness::BulkRatio => j.stiffness_value,
                JunctionStiffness::NormalLoad => {
                    (j.stiffness_value * self.junction_normal_force_bound()).sqrt()
                }
            },
        }
    }

    /// Stability limits of the leapfrog step, central-difference bound
    /// dt ≤ 2(√(1+ζ²) − ζ)/ω for each kind of block.
    pub fn stability_limit(&self) -> StabilityLimit {
        let m = self.mass;
        let bound = |stiffness: f64, damping: f64| {
            if stiffness <= 0.0 {
                return f64::INFINITY;
            }
            let omega = (stiffness / m).sqrt();
            let zeta = damping / (2.0 * m * omega);
            2.0 * ((1.0 + zeta * zeta).sqrt() - zeta) / omega
        };
        // The highest lattice mode (π, 0) sees 6k of springs and 12η of dashpots.
        let lattice = if self.n_blocks() > 1 {
            6.0 * self.k
        } else {
            0.0
        };
        let dashpots = if self.n_blocks() > 1 {
            12.0 * self.eta
        } else {
            0.0
        };
        let ns = self.junctions.map_or(0, |j| j.count) as f64;
        let interface_k = lattice + self.k_foundation + ns * self.junction_stiffness_bound();
        StabilityLimit {
            bulk_undamped: bound(lattice, 0.0),
            bulk: bound(lattice, dashpots + self.absolute_eta),
            interface: bound(interface_k, dashpots + self.absolute_eta),
            relaxation: bound(interface_k.max(lattice), dashpots + self.relax_eta),
            driven: match self.driver {
                Driver::SideSpring { stiffness, row, .. } => {
                    let base = if row == 0 { interface_k } else { lattice };
                    bound(base + stiffness, dashpots)
                }
                _ => f64::INFINITY,
            },
        }
    }

    /// Bytes of engine state at `real_bytes` per float and `coord_bytes`
    /// per accumulated coordinate (displacements, junction anchors): 8 and 8
    /// for f64, 4 and 8 for mixed f32, 4 and 4 for plain f32.
    pub fn memory_bytes(&self, real_bytes: usize, coord_bytes: usize) -> usize {
        let blocks = self.n_blocks() * (2 * coord_bytes + 4 * real_bytes + 4);
        let interface = self.nx * (2 * real_bytes + 4);
        let junctions = self.n_junctions() * (coord_bytes + real_bytes + 8);
        blocks + interface + junctions
    }

    /// Names of the force terms this scene uses (what the engines build).
    pub fn terms(&self) -> Vec<&'static str> {
        let mut t = Vec::new();
        if self.n_blocks() > 1 {
            t.push("springs");
            if self.eta > 0.0 {
                t.push(match self.damping_form {
                    DampingForm::Full => "damping(full)",
                    DampingForm::Bond => "damping(bond)",
                });
            }
        }
        if self.k_foundation > 0.0 {
            t.push("foundation");
        }
        if self.normal_force > 0.0 {
            t.push("normal_load");
        }
        if self.prep_steps > self.ramp_steps && self.relax_eta > 0.0 {
            t.push("relaxation_damping");
        }
        t.push(match self.driver {
            Driver::None => "no_driver",
            Driver::SideSpring { .. } => "side_spring",
            Driver::TopForce { .. } => "top_force",
            Driver::TopVelocity { .. } => "top_velocity",
        });
        t.push(match self.law {
            FrictionLaw::None => "frictionless",
            law => law.name(),
        });
        if self.trigger.is_some() {
            t.push("trigger");
        }
        if self.prestress.is_some() {
            t.push("interface_prestress");
        }
        if self.absolute_eta > 0.0 {
            t.push("absolute_damping");
        }
        if self.pulse.is_some() {
            t.push("initial_pulse");
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        ((a - b) / b).abs() < rel
    }

    #[test]
    fn table_s1_derived_numbers_match_model_md() {
        let m = Model::from_scenario(&Scenario::default_scene(), false).unwrap();
        assert!(close(m.mass, 4.2784e-5, 1e-4), "m = {}", m.mass);
        assert!(close(m.k, 1.35e7, 1e-9));
        assert!(close(m.eta, 7.600, 1e-3), "eta = {}", m.eta);
        assert!(close(m.k_foundation, 6.75e6, 1e-9));
        assert!(close(m.period, 11.19e-6, 1e-3), "T = {}", m.period);
        assert!(close(m.dt, 0.2238e-6, 1e-3), "dt = {}", m.dt);
        assert!(close(m.spacing, 2.5e-3, 1e-9));
        let lim = m.stability_limit();
        assert!(close(lim.bulk_undamped, 1.453e-6, 1e-3), "{lim:?}");
        assert!(close(m.shear_wave_speed(), 993.0, 1e-3));
        assert!(close(m.pressure_wave_speed(), 1720.0, 1e-3));
        assert!(close(
            m.rayleigh_wave_speed() / m.shear_wave_speed(),
            0.9194,
            1e-3
        ));
        assert_eq!(
            m.driver,
            Driver::SideSpring {
                stiffness: 4e6,
                row: 2,
                velocity: 4e-4
            }
        );
        assert!(close(m.lattice_youngs_modulus(), 3e9, 1e-12));
    }

    #[test]
    fn time_step_above_limit_is_refused_with_the_limit() {
        let s = Scenario::parse(
            crate::model::scenario::DEFAULT_SCENARIO,
            "t",
            &["time.dt_fraction=0.5".into()],
        )
        .unwrap();
        let err = Model::from_scenario(&s, false).unwrap_err().to_string();
        assert!(err.contains("stability limit"), "{err}");
        assert!(err.contains("--allow-unstable"), "{err}");
        assert!(Model::from_scenario(&s, true).is_ok());
    }
}
