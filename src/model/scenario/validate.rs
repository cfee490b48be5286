//! Range checks on a parsed scenario. Each problem names the key, the value,
//! the allowed range and, where the key is in the file, its line.

use super::{DriveMode, EdgeConstraint, FrictionLaw, Scenario};
use crate::model::friction::TableChecks;

/// Returns every problem found; empty when the scenario is valid.
/// `overridden` lists the keys set with `--set` (their line is the command line).
pub fn validate(s: &Scenario, text: &str, overridden: &[&str]) -> Vec<String> {
    let mut c = Checker {
        text,
        overridden,
        problems: Vec::new(),
    };
    let g = &s.geometry;
    c.positive("geometry.length", g.length);
    c.positive("geometry.height", g.height);
    c.positive("geometry.width", g.width);
    c.range_u("geometry.nx", g.nx, 1, 1 << 16);
    c.range_u("geometry.nz", g.nz, 1, 1 << 16);
    if g.nx > 1 && g.nz > 1 && g.length > 0.0 && g.height > 0.0 {
        let lx = g.length / (g.nx - 1) as f64;
        let lz = g.height / (g.nz - 1) as f64;
        if ((lx - lz) / lx).abs() > 1e-6 {
            let line = c.line("geometry.height");
            c.problems.push(format!(
                "geometry.height = {} gives spacing H/(nz-1) = {lz:e} m but L/(nx-1) = {lx:e} m: \
                 the lattice must be square (allowed: height = length*(nz-1)/(nx-1) = {}){line}",
                g.height,
                g.length * (g.nz - 1) as f64 / (g.nx - 1) as f64
            ));
        }
    }
    c.positive("material.density", s.material.density);
    c.positive("material.youngs_modulus", s.material.youngs_modulus);
    c.at_least("damping.ratio", s.damping.ratio, 0.0);
    // Bounded above by the stability limit, in Model.
    c.at_least("damping.absolute_ratio", s.damping.absolute_ratio, 0.0);
    c.at_least(
        "foundation.stiffness_ratio",
        s.foundation.stiffness_ratio,
        0.0,
    );
    // Without a foundation nothing carries the normal load (unless the
    // interface row is held in z): the slider falls through the track, which
    // no time step can fix.
    if s.foundation.stiffness_ratio == 0.0
        && s.loading.normal.force > 0.0
        && s.boundary.bottom != EdgeConstraint::FixZ
    {
        let line = c.line("foundation.stiffness_ratio");
        c.problems.push(format!(
            "foundation.stiffness_ratio = 0 with loading.normal.force = {} N: nothing carries \
             the normal load, and the slider would fall through the track (allowed: > 0, or \
             boundary.bottom = \"fix_z\"){line}",
            s.loading.normal.force
        ));
    }

    let f = &s.friction;
    c.at_least("friction.static_coefficient", f.static_coefficient, 0.0);
    c.at_least("friction.dynamic_coefficient", f.dynamic_coefficient, 0.0);
    if f.dynamic_coefficient > f.static_coefficient {
        let line = c.line("friction.dynamic_coefficient");
        c.problems.push(format!(
            "friction.dynamic_coefficient = {} exceeds friction.static_coefficient = {} \
             (allowed: 0 <= dynamic <= static){line}",
            f.dynamic_coefficient, f.static_coefficient
        ));
    }
    crate::model::friction::validate(f.law, &f.law_tables(), &mut c);

    let n = &s.loading.normal;
    c.at_least("loading.normal.force", n.force, 0.0);
    // Both edges pressed: a zero or negative edge load would need a
    // profile that pulls.
    c.range(
        "loading.normal.trailing_to_leading",
        n.trailing_to_leading,
        1e-3,
        1e3,
    );
    c.at_least("loading.normal.ramp_time", n.ramp_time, 0.0);
    c.at_least("loading.normal.relax_time", n.relax_time, 0.0);
    // The stability check bounds the extra damping (relaxation limit).
    c.at_least(
        "loading.normal.relax_damping_ratio",
        n.relax_damping_ratio,
        0.0,
    );

    let d = &s.loading.drive;
    let needs: &[&str] = match d.mode {
        DriveMode::SideSpring => &["stiffness", "height", "velocity"],
        DriveMode::TopForce => &["force_rate"],
        DriveMode::TopVelocity => &["velocity"],
        DriveMode::None => &[],
    };
    for (key, value) in [
        ("stiffness", d.stiffness),
        ("height", d.height),
        ("velocity", d.velocity),
        ("force_rate", d.force_rate),
    ] {
        let path = format!("loading.drive.{key}");
        match (needs.contains(&key), value) {
            (true, None) => c.problems.push(format!(
                "missing key {path}, required by loading.drive.mode = \"{}\"",
                drive_name(d.mode)
            )),
            (false, Some(v)) => {
                let line = c.line(&path);
                c.problems.push(format!(
                    "{path} = {v} is not used by loading.drive.mode = \"{}\" (allowed keys: {}){line}",
                    drive_name(d.mode),
                    needs.join(", ")
                ))
            }
            (true, Some(v)) => match key {
                "stiffness" => c.positive(&path, v),
                "height" => c.range(&path, v, 0.0, s.geometry.height),
                // Any finite force rate: a too-fast load shows as a
                // blow-up, stopped with its step, time and block.
                "force_rate" => c.finite(&path, v),
                // Bounded by the lattice's P-wave speed in Model.
                _ => c.finite(&path, v),
            },
            (false, None) => {}
        }
    }
    if let Some(t) = &s.loading.trigger {
        c.finite("loading.trigger.shear_prestress", t.shear_prestress);
        c.at_least("loading.trigger.force_width", t.force_width, 0.0);
        c.range(
            "loading.trigger.strip_length",
            t.strip_length,
            0.0,
            s.geometry.length,
        );
        c.finite("loading.trigger.strip_prestress", t.strip_prestress);
        if !matches!(f.law, FrictionLaw::Junctions | FrictionLaw::SingleJunction) {
            c.problems.push(format!(
                "[loading.trigger] sets junction forces, but friction.law = \"{}\" has no \
                 junctions (allowed with: junctions, single_junction)",
                f.law.name()
            ));
        }
    }

    if let Some(p) = &s.loading.prestress {
        validate_prestress(&mut c, s, p);
    }

    let t = &s.time;
    match (t.dt, t.dt_fraction) {
        // Bounded above by the stability limit, in Model.
        (Some(dt), None) => c.positive("time.dt", dt),
        (None, Some(fr)) => c.positive("time.dt_fraction", fr),
        (Some(_), Some(_)) => c.problems.push(
            "time.dt and time.dt_fraction are both set: give the time step one way only".into(),
        ),
        (None, None) => c
            .problems
            .push("missing key time.dt or time.dt_fraction: the time step is required".into()),
    }
    // Bounded above by an exact f64 step time, in Model.
    c.at_least("time.end", t.end, 0.0);
    if let Some(f) = &s.fast_forward {
        c.positive("fast_forward.quiet_energy", f.quiet_energy);
        c.at_least("fast_forward.quiet_time", f.quiet_time, 0.0);
        c.positive("fast_forward.lead_time", f.lead_time);
        c.positive("fast_forward.check_interval", f.check_interval);
        c.at_least("fast_forward.cascade_overshoot", f.cascade_overshoot, 0.0);
    }
    if t.fast_forward
        && !matches!(
            s.friction.law,
            FrictionLaw::Junctions | FrictionLaw::SingleJunction
        )
    {
        c.problems.push(format!(
            "time.fast_forward = true needs friction.law = \"junctions\" or \"single_junction\" \
             (got \"{}\": the quasi-static path of other laws is not built)",
            s.friction.law.name()
        ));
    }
    let o = &s.output;
    c.at_least("output.global_interval", o.global_interval, 0.0);
    c.at_least("output.interface_interval", o.interface_interval, 0.0);
    c.at_least("output.bulk_interval", o.bulk_interval, 0.0);
    c.at_least("output.fast_interval", o.fast_interval, 0.0);
    c.at_least("output.fast_slip_speed", o.fast_slip_speed, 0.0);
    c.at_least("output.checkpoint_interval", o.checkpoint_interval, 0.0);
    if let Some(p) = &s.pulse {
        c.range("pulse.center", p.center, 0.0, s.geometry.length);
        c.range("pulse.width", p.width, 1e-12, s.geometry.length);
        c.range(
            "pulse.amplitude",
            p.amplitude,
            -s.geometry.height,
            s.geometry.height,
        );
    }
    if let Some(start) = &s.start {
        c.range(
            "start.position",
            start.position,
            -MAX_START_POSITION,
            MAX_START_POSITION,
        );
    }
    c.problems
}

fn validate_prestress(c: &mut Checker<'_>, s: &Scenario, p: &super::Prestress) {
    let f = &s.friction;
    // Below the static threshold (τ̄ < 1), or the whole interface breaks
    // at once; below μd p (τ̄ < 0) a front cannot run.
    if !(p.tau_bar.is_finite() && (0.0..1.0).contains(&p.tau_bar)) {
        let line = c.line("loading.prestress.tau_bar");
        c.problems.push(format!(
            "loading.prestress.tau_bar = {} is out of range (allowed: 0 <= tau_bar < 1){line}",
            p.tau_bar
        ));
    }
    c.range(
        "loading.prestress.trigger_tau_bar",
        p.trigger_tau_bar,
        1.0 + 1e-9,
        10.0,
    );
    c.range_u(
        "loading.prestress.trigger_blocks",
        p.trigger_blocks,
        1,
        s.geometry.nx.saturating_sub(1).max(1),
    );
    if f.law == FrictionLaw::None || f.static_coefficient <= f.dynamic_coefficient {
        c.problems.push(format!(
            "[loading.prestress] is scaled between the dynamic and static friction levels, but \
             friction.law = \"{}\" with static_coefficient = {} and dynamic_coefficient = {} \
             has no gap between them (allowed: a friction law with static > dynamic)",
            f.law.name(),
            f.static_coefficient,
            f.dynamic_coefficient
        ));
    }
    if s.loading.trigger.is_some() {
        c.problems.push(
            "[loading.prestress] and [loading.trigger] both prestress the interface: give one \
             (allowed: either table)"
                .into(),
        );
    }
}

fn drive_name(m: DriveMode) -> &'static str {
    match m {
        DriveMode::SideSpring => "side_spring",
        DriveMode::TopForce => "top_force",
        DriveMode::TopVelocity => "top_velocity",
        DriveMode::None => "none",
    }
}

struct Checker<'a> {
    text: &'a str,
    overridden: &'a [&'a str],
    problems: Vec<String>,
}

impl Checker<'_> {
    fn line(&self, path: &str) -> String {
        if self.overridden.contains(&path) {
            return " (set on the command line)".to_string();
        }
        match line_of(self.text, path) {
            Some(n) => format!(" (line {n})"),
            None => " (set on the command line or defaulted)".to_string(),
        }
    }

    fn range(&mut self, path: &str, v: f64, lo: f64, hi: f64) {
        if !(v.is_finite() && v >= lo && v <= hi) {
            let line = self.line(path);
            self.problems.push(format!(
                "{path} = {v} is out of range (allowed: {lo} to {hi}){line}"
            ));
        }
    }

    fn at_least(&mut self, path: &str, v: f64, lo: f64) {
        if !(v.is_finite() && v >= lo) {
            let line = self.line(path);
            self.problems.push(format!(
                "{path} = {v} is out of range (allowed: a finite value >= {lo}){line}"
            ));
        }
    }

    fn finite(&mut self, path: &str, v: f64) {
        if !v.is_finite() {
            let line = self.line(path);
            self.problems.push(format!(
                "{path} = {v} is out of range (allowed: any finite value){line}"
            ));
        }
    }

    fn positive(&mut self, path: &str, v: f64) {
        if !(v.is_finite() && v > 0.0) {
            let line = self.line(path);
            self.problems.push(format!(
                "{path} = {v} is out of range (allowed: a finite value > 0){line}"
            ));
        }
    }

    fn range_u(&mut self, path: &str, v: u32, lo: u32, hi: u32) {
        if v < lo || v > hi {
            let line = self.line(path);
            self.problems.push(format!(
                "{path} = {v} is out of range (allowed: {lo} to {hi}){line}"
            ));
        }
    }
}

impl TableChecks for Checker<'_> {
    fn line(&self, key: &str) -> String {
        Checker::line(self, key)
    }
    fn problem(&mut self, text: String) {
        self.problems.push(text);
    }
    fn positive(&mut self, key: &str, v: f64) {
        Checker::positive(self, key, v)
    }
    fn at_least(&mut self, key: &str, v: f64, lo: f64) {
        Checker::at_least(self, key, v, lo)
    }
    fn range_u(&mut self, key: &str, v: u32, lo: u32, hi: u32) {
        Checker::range_u(self, key, v, lo, hi)
    }
}

/// 1-based line of `a.b.c` in simple TOML text (`[a.b]` header then `c = ...`).
pub fn line_of(text: &str, path: &str) -> Option<usize> {
    let (table, key) = match path.rsplit_once('.') {
        Some((t, k)) => (t, k),
        None => ("", path),
    };
    let mut current = String::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if let Some(h) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            current = h.trim().to_string();
            continue;
        }
        if current == table {
            if let Some((k, _)) = line.split_once('=') {
                if k.trim() == key {
                    return Some(i + 1);
                }
            }
        }
    }
    None
}

/// The farthest a slider may start along the track (m). At 1 m one f32 ulp of
/// a displacement is 60 nm, already 5 % of a Table S1 junction's stretch at
/// its threshold (1.2 µm).
pub const MAX_START_POSITION: f64 = 1.0;

#[cfg(test)]
mod tests {
    use super::line_of;

    #[test]
    fn finds_lines_of_nested_keys() {
        let text = "name = \"x\"\n[a]\nb = 1\n[a.c]\nb = 2 # note\n";
        assert_eq!(line_of(text, "name"), Some(1));
        assert_eq!(line_of(text, "a.b"), Some(3));
        assert_eq!(line_of(text, "a.c.b"), Some(5));
        assert_eq!(line_of(text, "a.d"), None);
    }
}
