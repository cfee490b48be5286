//! WGSL sources and how they are composed into modules, and the variant a
//! scene needs: which kernel runs and its override constants.
//!
//! Every file of `shaders/` says what it uses in an `// import:` line: other
//! files by name, or a slot that each module fills with one file of its
//! choice: `state` (the one-step kernels' ping-pong state, the persistent
//! kernel's in storage, the resident kernel's in workgroup memory, or the
//! tiled kernel's tile and halo), `junction_store` (where the junctions
//! are stepped: storage, or for the tiled kernel its halo's private
//! copies too), `lane_merge` (the junction lanes' sums merged in subgroups
//! before storage, or not: `LaneMerge`) and `coordinates` (double-single
//! or f64: the precision). A module
//! is the generated prelude of `layout.rs` and the closure of its entry
//! file's imports, each file once (WGSL declarations are order-free).
//! Every file validates with naga with only what it imports, so the
//! imports are all there is to know (`every_shader_validates_with_only_its_imports`).
//! Every module is generated in either precision (`GpuReal`: mixed f32 or
//! f64) from the same files: only the prelude's type aliases and the
//! coordinate functions differ.

use super::precision::GpuReal;
use crate::model::scenario::DampingForm;
use crate::model::{Driver, Model};

macro_rules! wgsl_files {
    ($($name:literal),* $(,)?) => {
        /// Every file of `shaders/`, by name (without `.wgsl`).
        pub const FILES: &[(&str, &str)] = &[$((
            $name,
            include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/", $name, ".wgsl")),
        )),*];
    };
}

wgsl_files!(
    "barriers",
    "bulk_forces",
    "bulk_patch",
    "common",
    "coord_f64",
    "double_single",
    "junction_store",
    "junction_tiled",
    "junctions",
    "lane_no_shuffle",
    "lane_partials",
    "lane_shuffle",
    "noted_blocks",
    "one_step",
    "one_step_lanes",
    "patch_items",
    "phase_clocks",
    "persistent",
    "record_batch",
    "record_buffers",
    "record_common",
    "record_step",
    "rng",
    "scene",
    "state_one_step",
    "state_by_index",
    "state_persistent",
    "state_resident",
    "state_tiled",
    "step_forces",
    "step_patches",
    "tiled",
    "verlet",
);

/// The generated shader of the friction laws' dispatch
/// (`crate::model::friction::wgsl_dispatch`).
pub const FRICTION_LAW_FILE: &str = "friction_law";

/// Every shader by name: the files of `shaders/`, the per-block friction
/// laws' files of `shaders/laws/` (declared by each law), and the
/// generated dispatch.
pub fn all_files() -> Vec<(&'static str, &'static str)> {
    let mut all: Vec<(&'static str, &'static str)> = FILES.to_vec();
    all.extend(crate::model::friction::wgsl_files());
    all.push((FRICTION_LAW_FILE, friction_dispatch()));
    all
}

fn friction_dispatch() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(crate::model::friction::wgsl_dispatch)
}

/// The text of shader file `name`.
pub fn file(name: &str) -> Option<&'static str> {
    if name == FRICTION_LAW_FILE {
        return Some(friction_dispatch());
    }
    FILES
        .iter()
        .copied()
        .chain(crate::model::friction::wgsl_files())
        .find(|(n, _)| *n == name)
        .map(|(_, text)| text)
}

/// The names in a file's `// import:` line (none for `(none)`).
pub fn imports(text: &str) -> Result<Vec<&str>, String> {
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix("// import:"))
        .ok_or("no `// import:` line")?;
    Ok(line
        .split(',')
        .map(str::trim)
        .filter(|n| !n.is_empty() && *n != "(none)")
        .collect())
}

/// The file each slot stands for in one module.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slots {
    pub state: &'static str,
    pub junction_store: &'static str,
    pub lane_merge: &'static str,
    pub coordinates: &'static str,
}

impl Slots {
    /// A kernel's slots: its state, the junctions in storage, `T`'s
    /// coordinates.
    pub fn kernel<T: GpuReal>(state: &'static str) -> Slots {
        Slots {
            state,
            junction_store: "junction_store",
            lane_merge: LaneMerge::Storage.file(),
            coordinates: T::COORDINATES,
        }
    }

    fn resolve<'a>(&self, name: &'a str) -> &'a str {
        match name {
            "state" => self.state,
            "junction_store" => self.junction_store,
            "lane_merge" => self.lane_merge,
            "coordinates" => self.coordinates,
            other => other,
        }
    }
}

/// The module of entry file `entry`: `prelude`, then the entry file and
/// every file it imports, directly or not, each once.
pub fn compose(prelude: &str, entry: &str, slots: &Slots) -> Result<String, String> {
    let mut order: Vec<&str> = Vec::new();
    let mut todo = vec![entry];
    while let Some(name) = todo.pop() {
        let name = slots.resolve(name);
        if order.contains(&name) {
            continue;
        }
        let text = file(name).ok_or_else(|| format!("no shader file {name}.wgsl"))?;
        order.push(name);
        let wanted = imports(text).map_err(|e| format!("{name}.wgsl: {e}"))?;
        todo.extend(wanted.into_iter().rev());
    }
    let mut module = String::from(prelude);
    for name in order {
        module += &format!("\n// ---- shaders/{name}.wgsl\n");
        module += file(name).unwrap_or_default();
    }
    Ok(module)
}

/// Where the persistent, resident and tiled kernels merge a block's
/// junction lane sums first: each lane's sum goes through storage to the
/// merging thread, or runs of 8 to 64 lanes merge in subgroups first (the
/// same tree, so the same sums; adapters with `Features::SUBGROUP`). The
/// one-step kernels merge theirs as they did either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LaneMerge {
    Storage,
    Shuffle,
}

impl LaneMerge {
    /// The file that fills the `lane_merge` slot.
    pub fn file(self) -> &'static str {
        match self {
            LaneMerge::Storage => "lane_no_shuffle",
            LaneMerge::Shuffle => "lane_shuffle",
        }
    }

    /// What naga needs to validate a module with these lanes.
    pub fn capabilities(self) -> naga::valid::Capabilities {
        match self {
            LaneMerge::Storage => naga::valid::Capabilities::empty(),
            LaneMerge::Shuffle => naga::valid::Capabilities::SUBGROUP,
        }
    }
}

/// A compute kernel: its entry point (the CPU twin's name) and source.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kernel {
    /// One step of any lattice per dispatch, ping-pong state buffers, one
    /// thread per block (no barrier: the software adapters' kernel).
    OneStep,
    /// The same with the junction lanes of each interface block in parallel
    /// (a workgroup per interface block).
    OneStepLanes,
    /// Many steps of a small lattice per dispatch, one workgroup per
    /// scene, the state in storage.
    Persistent,
    /// The persistent kernel's loop with each scene's u and v in its
    /// workgroup's memory for the whole dispatch (lattices that fit).
    Resident,
    /// Temporal blocking: a workgroup per column tile and scene steps its
    /// tile and a halo for several steps per dispatch (`tiled.wgsl`).
    Tiled,
}

impl Kernel {
    pub const ALL: [Kernel; 5] = [
        Kernel::OneStep,
        Kernel::OneStepLanes,
        Kernel::Persistent,
        Kernel::Resident,
        Kernel::Tiled,
    ];

    pub fn entry_point(self) -> &'static str {
        match self {
            Kernel::OneStep => "one_step",
            Kernel::OneStepLanes => "one_step_lanes",
            // One loop (persistent.wgsl), two places for the state.
            Kernel::Persistent | Kernel::Resident => "persistent_steps",
            Kernel::Tiled => "tiled_steps",
        }
    }

    /// The entry point dispatched before each of this kernel's own, if
    /// any: the tiled kernel's copy of its tiles' halos.
    pub fn gather_entry_point(self) -> Option<&'static str> {
        (self == Kernel::Tiled).then_some("tile_gather")
    }

    /// Many steps per dispatch, one workgroup per scene: the persistent
    /// kernel's loop, with its state in storage or workgroup memory.
    pub fn is_persistent(self) -> bool {
        matches!(self, Kernel::Persistent | Kernel::Resident)
    }

    /// Merges its junction lanes' sums through storage (`lane_partials.wgsl`),
    /// so `LaneMerge` chooses its module; the one-step kernels merge theirs
    /// in registers or workgroup memory, the same module either way.
    pub fn merges_lanes_through_storage(self) -> bool {
        matches!(self, Kernel::Persistent | Kernel::Resident | Kernel::Tiled)
    }

    /// Separates a step's phases with `workgroup_storage_barrier`
    /// (`barriers.wgsl`): what one thread writes to storage, another of
    /// its workgroup reads in the next phase. The one-step kernels end a
    /// step with their dispatch.
    pub fn has_phase_barriers(self) -> bool {
        matches!(self, Kernel::Persistent | Kernel::Resident | Kernel::Tiled)
    }

    /// The full WGSL module of this kernel: it steps the scenes of one
    /// lattice shape, one or many, per dispatch (`shaders/scene.wgsl`).
    pub fn source<T: GpuReal>(self) -> String {
        self.source_with::<T>(LaneMerge::Storage)
    }

    /// The module with its junction lanes merged as `lanes` says.
    pub fn source_with<T: GpuReal>(self, lanes: LaneMerge) -> String {
        let (state, entry) = match self {
            Kernel::OneStep => ("state_one_step", "one_step"),
            Kernel::OneStepLanes => ("state_one_step", "one_step_lanes"),
            Kernel::Persistent => ("state_persistent", "persistent"),
            Kernel::Resident => ("state_resident", "persistent"),
            Kernel::Tiled => ("state_tiled", "tiled"),
        };
        let mut slots = Slots::kernel::<T>(state);
        slots.lane_merge = lanes.file();
        if self == Kernel::Tiled {
            slots.junction_store = "junction_tiled";
        }
        compose(&super::layout::wgsl_prelude::<T>(), entry, &slots)
            .expect("the shader files' imports resolve (tested)")
    }
}

/// The override constants of a scene: terms it does not use are compiled out.
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    pub constants: Vec<(&'static str, f64)>,
}

impl Variant {
    pub fn for_model(m: &Model) -> Variant {
        let damping = if m.eta == 0.0 || m.n_blocks() == 1 {
            0.0
        } else {
            match m.damping_form {
                DampingForm::Full => 1.0,
                DampingForm::Bond => 2.0,
            }
        };
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        let top_loads = m.normal_force != 0.0
            || m.trigger.is_some()
            || matches!(m.driver, Driver::TopForce { .. });
        let law = m.law.declaration().kernel as f64;
        Variant {
            constants: vec![
                ("FRICTION_LAW", law),
                ("DAMPING_FORM", damping),
                ("USE_FOUNDATION", flag(m.k_foundation > 0.0)),
                ("USE_TOP_LOADS", flag(top_loads)),
                (
                    "USE_SIDE_SPRING",
                    flag(matches!(m.driver, Driver::SideSpring { .. })),
                ),
                (
                    "USE_RELAXATION",
                    flag(
                        (m.relax_eta > 0.0 && m.prep_steps > m.ramp_steps) || m.absolute_eta > 0.0,
                    ),
                ),
                ("USE_PRESTRESS", flag(m.prestress.is_some())),
            ],
        }
    }

    /// `CONST=value, ...`.
    pub fn describe(&self) -> String {
        self.constants
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(",")
    }
}

/// Parses and validates a kernel's module with naga (no adapter needed).
pub fn validate_kernel<T: GpuReal>(phase: Kernel) -> Result<naga::Module, String> {
    validate_kernel_with::<T>(phase, LaneMerge::Storage)
}

/// The same with its junction lanes merged as `lanes` says.
pub fn validate_kernel_with<T: GpuReal>(
    phase: Kernel,
    lanes: LaneMerge,
) -> Result<naga::Module, String> {
    let src = phase.source_with::<T>(lanes);
    let module = naga::front::wgsl::parse_str(&src)
        .map_err(|e| format!("{}: {}", phase.entry_point(), e.emit_to_string(&src)))?;
    let caps = T::CAPABILITIES | lanes.capabilities();
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
        .validate(&module)
        .map_err(|e| format!("{}: {}", phase.entry_point(), e.emit_to_string(&src)))?;
    for entry in std::iter::once(phase.entry_point()).chain(phase.gather_entry_point()) {
        if !module.entry_points.iter().any(|e| e.name == entry) {
            return Err(format!(
                "{}: entry point {entry} missing",
                phase.entry_point()
            ));
        }
    }
    Ok(module)
}

/// What is wrong with a shader's `CPU twin:` line (the first in the file):
/// `// CPU twin: src/PATH.rs NAME, NAME ...`, each NAME (`Type::item` or
/// `item`) defined in PATH under `root`. Empty when the twin is there.
pub fn twin_errors(file: &str, wgsl: &str, root: &std::path::Path) -> Vec<String> {
    let Some(at) = wgsl.find("CPU twin: ") else {
        return vec![format!("{file}: no `CPU twin:` line")];
    };
    let rest = &wgsl[at + "CPU twin: ".len()..];
    let rest = rest.lines().next().unwrap_or("");
    let mut words = rest.split([' ', ',']).filter(|w| !w.is_empty());
    let path = words.next().unwrap_or("").trim_end_matches('.');
    let Ok(source) = std::fs::read_to_string(root.join(path)) else {
        return vec![format!("{file}: CPU twin {path:?} does not exist")];
    };
    // Names up to the end of the line, a word that ends a sentence, or
    // anything that is not a name ("(the host's layout)").
    let mut names = Vec::new();
    for word in words {
        let name = word.trim_end_matches('.');
        let is_name = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':');
        if !is_name {
            break;
        }
        names.push(name);
        if word.ends_with('.') {
            break;
        }
    }
    if names.is_empty() {
        return vec![format!("{file}: CPU twin {path} names no function or type")];
    }
    let defines = |item: &str| {
        ["fn", "struct", "trait", "enum", "const", "type"]
            .iter()
            .any(|kw| source.contains(&format!("{kw} {item}")))
    };
    names
        .into_iter()
        .filter(|name| !defines(name.rsplit("::").next().unwrap_or(name)))
        .map(|name| format!("{file}: {name} is not defined in {path}"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The slots a file stands for: composed alone, it fills them itself.
    fn slots_for<T: GpuReal>(name: &'static str) -> Slots {
        let mut slots = Slots::kernel::<T>("state_one_step");
        match name {
            "state_one_step" | "state_persistent" | "state_resident" => slots.state = name,
            "persistent" | "lane_partials" => slots.state = "state_persistent",
            "state_tiled" | "tiled" => {
                slots.state = "state_tiled";
                slots.junction_store = "junction_tiled";
            }
            "junction_store" => slots.junction_store = name,
            "lane_shuffle" | "lane_no_shuffle" => slots.lane_merge = name,
            "junction_tiled" => {
                slots.state = "state_tiled";
                slots.junction_store = name;
            }
            "double_single" | "coord_f64" => slots.coordinates = name,
            _ => {}
        }
        slots
    }

    fn naga_errors<T: GpuReal>(src: &str) -> Option<String> {
        naga_errors_with::<T>(src, LaneMerge::Storage)
    }

    fn naga_errors_with<T: GpuReal>(src: &str, lanes: LaneMerge) -> Option<String> {
        let module = match naga::front::wgsl::parse_str(src) {
            Ok(m) => m,
            Err(e) => return Some(e.emit_to_string(src)),
        };
        let caps = T::CAPABILITIES | lanes.capabilities();
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
            .validate(&module)
            .err()
            .map(|e| e.emit_to_string(src))
    }

    fn alone<T: GpuReal>() -> Vec<String> {
        let prelude = crate::engines::gpu::layout::wgsl_prelude::<T>();
        all_files()
            .into_iter()
            .filter(|(name, _)| match *name {
                "double_single" => T::COORDINATES == "double_single",
                "coord_f64" => T::COORDINATES == "coord_f64",
                _ => true,
            })
            .filter_map(|(name, _)| {
                let src = compose(&prelude, name, &slots_for::<T>(name)).unwrap();
                // Only the subgroup file may use subgroup operations.
                let lanes = match name {
                    "lane_shuffle" => LaneMerge::Shuffle,
                    _ => LaneMerge::Storage,
                };
                naga_errors_with::<T>(&src, lanes)
                    .map(|e| format!("{name}.wgsl ({}): {e}", T::NAME))
            })
            .collect()
    }

    /// The imports are explicit and complete: each file, composed with
    /// only what it imports (and the prelude), validates, in both
    /// precisions. A file that drops an import fails (the control).
    #[test]
    fn every_shader_validates_with_only_its_imports() {
        let errors: Vec<String> = alone::<f32>().into_iter().chain(alone::<f64>()).collect();
        assert!(errors.is_empty(), "{}", errors.join("\n"));
        let junctions = file("junctions").unwrap();
        let without_rng = junctions.replace(", rng,", ",");
        assert_ne!(without_rng, junctions);
        let prelude = crate::engines::gpu::layout::wgsl_prelude::<f32>();
        let slots = slots_for::<f32>("junctions");
        let mut src = prelude.clone();
        for (name, text) in all_files() {
            let wanted = compose("", "junctions", &slots).unwrap();
            if wanted.contains(&format!("// ---- shaders/{name}.wgsl\n")) && name != "rng" {
                src += if name == "junctions" {
                    &without_rng
                } else {
                    text
                };
            }
        }
        assert!(naga_errors::<f32>(&src).is_some(), "junctions needs rng");
    }

    fn wgsl_names(dir: &std::path::Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .filter_map(|e| {
                let name = e.unwrap().file_name().to_string_lossy().to_string();
                name.strip_suffix(".wgsl").map(str::to_string)
            })
            .collect();
        names.sort();
        names
    }

    /// FILES lists every file of shaders/, the laws every file of
    /// shaders/laws/, and an unknown import is refused.
    #[test]
    fn every_shader_file_is_registered_and_imports_resolve() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
        let mut registered: Vec<String> = FILES.iter().map(|(n, _)| n.to_string()).collect();
        registered.sort();
        assert_eq!(wgsl_names(&root), registered);
        let mut laws: Vec<String> = crate::model::friction::wgsl_files()
            .map(|(n, _)| n.to_string())
            .collect();
        laws.sort();
        assert_eq!(wgsl_names(&root.join("laws")), laws);
        for (name, text) in all_files() {
            let wanted = imports(text).unwrap_or_else(|e| panic!("{name}: {e}"));
            for w in wanted {
                let known = file(w).is_some()
                    || ["state", "junction_store", "lane_merge", "coordinates"].contains(&w);
                assert!(known, "{name}.wgsl imports unknown {w}");
            }
        }
        let slots = Slots::kernel::<f32>("state_one_step");
        assert!(compose("", "no_such_file", &slots).is_err());
    }

    /// Every file in shaders/ names its CPU twin, and the twin is there;
    /// a twin that was renamed or moved is flagged (the control).
    #[test]
    fn every_shader_names_a_cpu_twin_that_exists() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut files: Vec<_> = ["shaders", "shaders/laws"]
            .iter()
            .flat_map(|dir| std::fs::read_dir(root.join(dir)).unwrap())
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "wgsl"))
            .collect();
        files.sort();
        assert!(files.len() >= 19, "{files:?}");
        let mut errors: Vec<String> = files
            .iter()
            .flat_map(|p| {
                let name = p.file_name().unwrap().to_string_lossy().to_string();
                twin_errors(&name, &std::fs::read_to_string(p).unwrap(), root)
            })
            .collect();
        errors.extend(twin_errors(
            FRICTION_LAW_FILE,
            file(FRICTION_LAW_FILE).unwrap(),
            root,
        ));
        assert!(errors.is_empty(), "{errors:#?}");
        let good = "// CPU twin: src/engines/kernels/verlet.rs verlet.";
        assert!(twin_errors("x", good, root).is_empty());
        for bad in [
            "// no twin named",
            "// CPU twin: src/cpu/verlet.rs verlet.",
            "// CPU twin: src/engines/kernels/verlet.rs leapfrog.",
            "// CPU twin: src/engines/kernels/verlet.rs.",
        ] {
            assert_eq!(twin_errors("x", bad, root).len(), 1, "{bad}");
        }
    }

    fn validate_all<T: GpuReal>() {
        for kernel in Kernel::ALL {
            for lanes in [LaneMerge::Storage, LaneMerge::Shuffle] {
                validate_kernel_with::<T>(kernel, lanes)
                    .unwrap_or_else(|e| panic!("{} {lanes:?}: {e}", T::NAME));
            }
        }
    }

    #[test]
    fn every_shader_parses_and_validates_with_naga() {
        validate_all::<f32>();
    }

    #[test]
    fn every_shader_validates_in_f64_too() {
        validate_all::<f64>();
    }

    /// The kernels that merge lanes in subgroups need the SUBGROUP
    /// capability (the adapter's `Features::SUBGROUP`), and only they: the
    /// storage modules validate without it (`validate_all`), and the
    /// one-step kernels are the same module either way.
    #[test]
    fn lane_shuffles_need_the_subgroup_capability_and_only_their_kernels_use_them() {
        let (stored, own): (Vec<Kernel>, Vec<Kernel>) = Kernel::ALL
            .into_iter()
            .partition(|k| k.merges_lanes_through_storage());
        for kernel in stored {
            let src = kernel.source_with::<f32>(LaneMerge::Shuffle);
            assert!(src.contains("subgroupShuffleXor"), "{kernel:?}");
            assert!(naga_errors::<f32>(&src).is_some(), "{kernel:?}");
            assert!(naga_errors_with::<f32>(&src, LaneMerge::Shuffle).is_none());
            let storage = kernel.source::<f32>();
            for op in ["subgroupShuffleXor(", "subgroupAdd(", "subgroupAll("] {
                assert!(!storage.contains(op), "{kernel:?}: {op}");
            }
        }
        assert_eq!(own, [Kernel::OneStep, Kernel::OneStepLanes]);
        for kernel in own {
            assert_eq!(
                kernel.source_with::<f32>(LaneMerge::Shuffle),
                kernel.source::<f32>()
            );
        }
    }

    /// Every kernel family's pipeline layout (its modules' bindings that
    /// their entry points use, both groups) binds at most the storage
    /// arrays the engine asks an adapter for (`context::STORAGE_BINDINGS`),
    /// in both precisions and both lane merges, and the tiled kernel's binds
    /// exactly that many: an adapter that passes the check at start-up can
    /// bind every kernel, and the check asks no more than they need.
    #[test]
    fn every_kernel_binds_at_most_the_storage_arrays_the_adapter_is_asked_for() {
        use super::super::bindings::Bindings;
        use super::super::context::STORAGE_BINDINGS;
        fn family<T: GpuReal>(kernels: &[Kernel], lanes: LaneMerge) -> u32 {
            kernels
                .iter()
                .map(|k| Bindings::reflect(&k.source_with::<T>(lanes)).unwrap())
                .reduce(Bindings::union)
                .unwrap()
                .storage_count()
        }
        let families: [&[Kernel]; 3] = [
            &[Kernel::OneStep, Kernel::OneStepLanes],
            &[Kernel::Persistent, Kernel::Resident],
            &[Kernel::Tiled],
        ];
        for kernels in families {
            for lanes in [LaneMerge::Storage, LaneMerge::Shuffle] {
                for n in [family::<f32>(kernels, lanes), family::<f64>(kernels, lanes)] {
                    assert!(
                        n <= STORAGE_BINDINGS,
                        "{kernels:?} {lanes:?}: {n} storage arrays"
                    );
                }
            }
        }
        assert_eq!(
            family::<f32>(&[Kernel::Tiled], LaneMerge::Storage),
            STORAGE_BINDINGS
        );
    }

    /// The kernels index a scene's status words by the names the prelude
    /// gives `GpuStatus`'s fields (`STATUS_<FIELD>`), never by a number, so
    /// a counter cannot drift from the word the host reads; the words per
    /// scene are `GpuStatus`'s, an even count (the status copies are
    /// followed by 8-byte timestamps).
    #[test]
    fn the_kernels_name_the_status_words_of_gpu_status() {
        use super::super::layout::{GpuStatus, GpuStruct};
        let words = std::mem::size_of::<GpuStatus>() / 4;
        assert_eq!(words % 2, 0);
        let prelude = super::super::layout::wgsl_prelude::<f32>();
        assert!(prelude.contains(&format!("const STATUS_WORDS: u32 = {words}u;")));
        for (name, _, offset) in GpuStatus::fields() {
            let line = format!(
                "const STATUS_{}: u32 = {}u;",
                name.to_uppercase(),
                offset / 4
            );
            assert!(prelude.contains(&line), "the prelude lacks {line}");
        }
        // Every index into `status` adds a named word to a base.
        let mut indexed = 0;
        for (name, text) in all_files() {
            for (at, _) in text.match_indices("status[") {
                let index = &text[at + "status[".len()..];
                let index = &index[..index.find(']').unwrap()];
                assert!(
                    index.contains("STATUS_") && !index.chars().any(|ch| ch.is_ascii_digit()),
                    "{name}.wgsl indexes status[{index}]: name the word"
                );
                indexed += 1;
            }
        }
        assert!(indexed >= 10, "{indexed} status indices found");
    }

    /// The f64 kernels need the FLOAT64 capability, so the test above
    /// validates f64 code (the mixed ones validate without it).
    #[test]
    fn f64_kernels_need_the_float64_capability() {
        let one_step = |caps| {
            let src = Kernel::OneStep.source::<f64>();
            let module = naga::front::wgsl::parse_str(&src).unwrap();
            naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
                .validate(&module)
                .is_ok()
        };
        assert!(!one_step(naga::valid::Capabilities::empty()));
        assert!(one_step(naga::valid::Capabilities::FLOAT64));
    }
}
