//! What the driver's compiler gives each GPU kernel on Table S1, in one
//! command, for anyone with a GPU:
//!
//!     cargo bench --bench gpu_registers
//!
//! (on the lent GPU machine: the packed `gpu_registers` binary). For each
//! launch (kernel, threads, patches, lanes), in mixed f32 and f64, on the
//! shipped Table S1 scene (junctions) and with Coulomb friction, it
//! compiles the step kernel the engine would compile on the adapter (the
//! same WGSL, override constants and wgpu options) on a Vulkan device of
//! its own with VK_KHR_pipeline_executable_properties, and prints what the
//! driver reports: the registers a thread holds, spills, code size and the
//! rest, as Markdown. On NVIDIA it adds the workgroups an SM holds by
//! registers and threads (`driver_stats::nvidia_workgroups_per_sm`): 1 at
//! 256 threads means Table S1 scenes cannot share an SM, whatever their
//! step costs (docs/gpu-kernels.md, "What limits an ensemble").
//!
//! It runs nothing on the device and takes seconds. lavapipe reports no
//! statistics; it then says so and exits with 1.
//!
//! SLIPFRONT_GPU_REGISTERS_DEVICE=RADV asks the first Vulkan device whose
//! name contains that text, and compiles the kernels as the engine would
//! build them there, without opening wgpu: with Mesa's radv installed and
//! RADV_FORCE_FAMILY=navi21 (or another family), AMD's compiler on Mesa's
//! null device, on a machine without a GPU. Its registers are AMD's
//! (VGPRs), not NVIDIA's: they compare kernels with each other, not with
//! an SM.
//! SLIPFRONT_GPU_REGISTERS_LAUNCHES=resident/1024,persistent/256 compiles
//! only those launches.
//! SLIPFRONT_GPU_REGISTERS_DUMP=DIR also writes what the driver gives of
//! each kernel's internal forms (RADV: NIR, ACO IR, disassembly; NVIDIA:
//! whatever its driver gives) into DIR, a file per kernel and form, and
//! lists them: the instructions a kernel's loops issue, read off the
//! hardware's own compiler.
//! SLIPFRONT_GPU_REGISTERS_BARRIERS=device compiles the phase barriers as
//! wgpu writes them, with device scope (`GpuOptions::workgroup_barriers`
//! off), where the engine would give them workgroup scope.
//! SLIPFRONT_GPU_REGISTERS_ARITHMETIC=guarded compiles the kernels as wgpu
//! writes them (`GpuOptions::arithmetic` `Wgpu`; otherwise `Strict`): mixed f32 with its
//! fusion guards, f64 plain, where the engine would forbid contraction.
//! SLIPFRONT_GPU_REGISTERS_PHASE_CLOCKS=1 compiles the persistent, resident
//! and tiled kernels with their phase clocks (`GpuOptions::phase_clocks`),
//! where the device has VK_KHR_shader_clock: what timing them costs in
//! registers (the one-step kernels, which have no phases, are listed as
//! not built).
//! SLIPFRONT_GPU_REGISTERS_SET=TWO_LANES_A_ROUND=0,KEEP_JUNCTION_SUMS=0
//! compiles every kernel with those override constants changed, where it
//! has them: what a kernel's options cost in registers (TILE_RECORDS=1:
//! the tiled kernel's recording variant, which a run with an output file
//! steps with).

use slipfront::engines::gpu::compile::KernelSource;
use slipfront::engines::gpu::driver_stats::{
    nvidia_workgroups_per_sm, DeviceChoice, Executable, StatsDevice, NVIDIA,
};
use slipfront::engines::gpu::kernel_choice::Launch;
use slipfront::engines::gpu::{context, AdapterTraits, Arithmetic, GpuEngine, GpuOptions, GpuReal};
use slipfront::model::scenario::built_in;
use slipfront::{Model, Scenario};

/// The launches compiled by default: every kernel at the thread counts
/// `auto` and the ensemble bench time, with and without bond patches and
/// lane shuffles where they change the module, and the tiled kernel with
/// its rounds chained (at a small halo too, as `auto` times it where
/// chaining wins).
const LAUNCHES: &[&str] = &[
    "one-step",
    "one-step/bond-patches",
    "one-step-lanes",
    "persistent/256",
    "persistent/512",
    "persistent/1024",
    "persistent/1024/2-scenes",
    "persistent/256/bond-patches",
    "persistent/256/lanes-in-storage",
    "resident/256",
    "resident/512",
    "resident/1024",
    "resident/256/bond-patches",
    "resident/1024/bond-patches",
    "persistent/256/lane-run-4",
    "resident/256/lane-run-4",
    "resident/1024/lane-run-4",
    "tiled/256/8x4",
    "tiled/256/16x4",
    "tiled/1024/16x4",
    "tiled/256/8x4/chained",
    "tiled/256/16x1/chained",
    "tiled/256/8x4/chained/lane-run-4",
];

fn launches() -> Vec<Launch> {
    let names: Vec<String> = match std::env::var("SLIPFRONT_GPU_REGISTERS_LAUNCHES") {
        Ok(list) => list.split(',').map(|s| s.trim().to_string()).collect(),
        Err(_) => LAUNCHES.iter().map(|s| s.to_string()).collect(),
    };
    names
        .iter()
        .map(|n| {
            Launch::named(n).unwrap_or_else(|| {
                panic!("SLIPFRONT_GPU_REGISTERS_LAUNCHES: `{n}` is not a launch name")
            })
        })
        .collect()
}

/// `SLIPFRONT_GPU_REGISTERS_SET`: NAME=VALUE pairs, comma-separated.
fn constants_set() -> Vec<(String, f64)> {
    let Ok(list) = std::env::var("SLIPFRONT_GPU_REGISTERS_SET") else {
        return Vec::new();
    };
    list.split(',')
        .filter(|pair| !pair.trim().is_empty())
        .map(|pair| {
            let (name, value) = pair.split_once('=').unwrap_or_else(|| {
                panic!("SLIPFRONT_GPU_REGISTERS_SET: `{pair}` is not NAME=VALUE")
            });
            let value = value.trim().parse().unwrap_or_else(|_| {
                panic!("SLIPFRONT_GPU_REGISTERS_SET: `{value}` is not a number")
            });
            (name.trim().to_string(), value)
        })
        .collect()
}

fn scene(set: &[&str]) -> Model {
    let text = built_in("tromborg2014_precursors").expect("shipped scene");
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let s = Scenario::parse(text, "table S1", &set).expect("scene");
    Model::from_scenario(&s, false).expect("model")
}

/// The threads a kernel's workgroup has, from its constants (the one-step
/// kernels' fixed workgroup otherwise).
fn threads(k: &KernelSource) -> u64 {
    k.constant("PERSISTENT_THREADS")
        .or(k.constant("TILE_THREADS"))
        .map(|t| t as u64)
        .unwrap_or(slipfront::engines::gpu::layout::WORKGROUP as u64)
}

/// The statistics that say how much a thread spills, where the driver
/// names them (NVIDIA: local memory; AMD: spilled registers, scratch).
fn spills(e: &Executable) -> String {
    let parts: Vec<String> = e
        .statistics
        .iter()
        .filter(|s| {
            let n = s.name.to_lowercase();
            n.contains("spill") || n.contains("local memory") || n.contains("scratch")
        })
        .map(|s| format!("{} {}", s.name, s.value))
        .collect();
    if parts.is_empty() {
        "–".into()
    } else {
        parts.join(", ")
    }
}

fn all_statistics(e: &Executable) -> String {
    e.statistics
        .iter()
        .map(|s| format!("{} {}", s.name, s.value))
        .collect::<Vec<_>>()
        .join("; ")
}

struct Table<'a> {
    device: &'a StatsDevice,
    traits: AdapterTraits,
    /// Override constants changed from the engine's (`SLIPFRONT_GPU_REGISTERS_SET`).
    set: Vec<(String, f64)>,
    /// The phase barriers with naga's device scope (`SLIPFRONT_GPU_REGISTERS_BARRIERS`).
    device_barriers: bool,
    /// wgpu's modules: mixed f32 guarded, f64 plain (`SLIPFRONT_GPU_REGISTERS_ARITHMETIC`).
    guarded: bool,
    /// The kernels with their phase clocks (`SLIPFRONT_GPU_REGISTERS_PHASE_CLOCKS`).
    phase_clocks: bool,
    /// Why a row did not compile, each reason once.
    not_built: Vec<String>,
    /// Where the driver's internal representations go (SLIPFRONT_GPU_REGISTERS_DUMP).
    dump_dir: Option<std::path::PathBuf>,
    /// The files written there.
    dumped: Vec<String>,
}

impl Table<'_> {
    fn rows<T: GpuReal>(&mut self, scene_name: &str, model: &Model, launch: Launch) {
        let opts = GpuOptions {
            workgroup_barriers: !self.device_barriers,
            arithmetic: match self.guarded {
                true => Arithmetic::Wgpu,
                false => Arithmetic::Strict,
            },
            phase_clocks: self.phase_clocks,
            ..launch.options(GpuOptions::default())
        };
        let sources = match GpuEngine::<T>::kernel_sources_on(model, opts, &self.traits) {
            Ok(s) => s,
            Err(e) => {
                self.skip(scene_name, T::NAME, launch, &e.to_string());
                return;
            }
        };
        for mut k in sources {
            for (name, value) in &self.set {
                if let Some(slot) = k.constants.iter_mut().find(|(n, _)| n == name) {
                    slot.1 = *value;
                } else if k.source.contains(&format!("override {name}:")) {
                    // One the module declares and the pipeline leaves at
                    // its default (a recording variant's: TILE_RECORDS).
                    k.constants.push((name.clone(), *value));
                }
            }
            let k = &k;
            match self.device.compile(k) {
                Ok(executables) => {
                    for e in &executables {
                        self.dump(scene_name, T::NAME, launch, k, e);
                        let regs = e.registers();
                        let per_sm = match regs {
                            Some(r) if self.device.vendor_id() == NVIDIA => {
                                nvidia_workgroups_per_sm(r, threads(k)).to_string()
                            }
                            _ => "–".into(),
                        };
                        println!(
                            "| {scene_name} | {} | {} | {} | {} | {:?} | {} | {} | {} | {per_sm} | {} |",
                            T::NAME,
                            launch.name(),
                            k.entry,
                            threads(k),
                            k.build.lanes,
                            e.subgroup_size,
                            regs.map_or("–".into(), |r| r.to_string()),
                            spills(e),
                            all_statistics(e),
                        );
                    }
                }
                Err(e) => self.skip(scene_name, T::NAME, launch, &e),
            }
        }
    }

    /// Writes `e`'s internal representations into the dump folder, if
    /// one was asked for, a file each, and notes their names.
    fn dump(
        &mut self,
        scene_name: &str,
        precision: &str,
        launch: Launch,
        k: &KernelSource,
        e: &Executable,
    ) {
        let Some(dir) = &self.dump_dir else {
            return;
        };
        for r in &e.representations {
            let name = format!(
                "{scene_name}-{precision}-{}-{}-{}-{}.{}",
                launch.name(),
                k.entry,
                e.name,
                r.name,
                if r.is_text { "txt" } else { "bin" }
            );
            // Runs of other characters as one underscore.
            let mut file = String::new();
            for ch in name.chars() {
                if ch.is_ascii_alphanumeric() || ch == '.' || ch == '-' {
                    file.push(ch);
                } else if !file.ends_with('_') {
                    file.push('_');
                }
            }
            let path = dir.join(file);
            match std::fs::write(&path, &r.data) {
                Ok(()) => self
                    .dumped
                    .push(format!("{} ({} bytes)", path.display(), r.data.len())),
                Err(err) => self
                    .dumped
                    .push(format!("{}: not written: {err}", path.display())),
            }
        }
    }

    fn skip(&mut self, scene_name: &str, precision: &str, launch: Launch, why: &str) {
        println!(
            "| {scene_name} | {precision} | {} | – | – | – | – | – | – | – | not built (see below) |",
            launch.name()
        );
        let why = why.to_string();
        if !self.not_built.contains(&why) {
            self.not_built.push(why);
        }
    }
}

fn main() {
    let named = std::env::var("SLIPFRONT_GPU_REGISTERS_DEVICE").ok();
    // The engine's own adapter unless another device is named: then wgpu
    // is not opened at all (Mesa's null devices cannot run it).
    let (mut device, traits) = match &named {
        Some(text) => StatsDevice::open(DeviceChoice::NameContains(text)).map(|d| {
            let t = d.traits().clone();
            (d, t)
        }),
        None => context::shared()
            .map_err(|e| e.to_string())
            .and_then(|ctx| {
                let choice = DeviceChoice::Ids {
                    vendor: ctx.info.vendor,
                    device: ctx.info.device,
                };
                StatsDevice::open(choice).map(|d| (d, AdapterTraits::of(&ctx)))
            }),
    }
    .unwrap_or_else(|why| {
        println!("No driver statistics: {why}");
        std::process::exit(1);
    });
    let dump_dir = std::env::var_os("SLIPFRONT_GPU_REGISTERS_DUMP").map(std::path::PathBuf::from);
    if let Some(dir) = &dump_dir {
        std::fs::create_dir_all(dir).unwrap_or_else(|e| {
            panic!(
                "SLIPFRONT_GPU_REGISTERS_DUMP: cannot make {}: {e}",
                dir.display()
            )
        });
        device.capture_representations(true);
    }
    println!(
        "## The driver's figures for each kernel: {} ({})\n",
        device.name(),
        device.driver()
    );
    println!(
        "Compiled as the engine builds them on this device (software adapter: {}, subgroups: \
         {}, workgroup memory: {} bytes). Registers: a thread's, as the driver reports them \
         (NVIDIA \"Register Count\", AMD \"VGPRs\"). Workgroups/SM: by registers and threads \
         on an NVIDIA SM of compute capability 8.0–9.0 (65,536 registers), not by workgroup \
         memory.\n",
        traits.software, traits.subgroups, traits.limits.max_compute_workgroup_storage_size
    );
    println!(
        "| scene | precision | launch | entry | threads | lanes | subgroup | registers | spills | workgroups/SM | all statistics |"
    );
    println!("| --- | --- | --- | --- | ---: | --- | ---: | ---: | --- | ---: | --- |");
    let mut table = Table {
        device: &device,
        traits,
        set: constants_set(),
        device_barriers: match std::env::var("SLIPFRONT_GPU_REGISTERS_BARRIERS").as_deref() {
            Ok("device") => true,
            Ok("workgroup") | Err(_) => false,
            Ok(other) => {
                panic!("SLIPFRONT_GPU_REGISTERS_BARRIERS: `{other}` is not device or workgroup")
            }
        },
        guarded: match std::env::var("SLIPFRONT_GPU_REGISTERS_ARITHMETIC").as_deref() {
            Ok("guarded") => true,
            Ok("strict") | Err(_) => false,
            Ok(other) => {
                panic!("SLIPFRONT_GPU_REGISTERS_ARITHMETIC: `{other}` is not strict or guarded")
            }
        },
        phase_clocks: match std::env::var("SLIPFRONT_GPU_REGISTERS_PHASE_CLOCKS").as_deref() {
            Ok("1") => true,
            Ok("0") | Err(_) => false,
            Ok(other) => {
                panic!("SLIPFRONT_GPU_REGISTERS_PHASE_CLOCKS: `{other}` is neither 0 nor 1")
            }
        },
        not_built: Vec::new(),
        dump_dir,
        dumped: Vec::new(),
    };
    let scenes = [
        ("Ns = 100 (as shipped)", scene(&[])),
        ("Coulomb", scene(&["friction.law=coulomb"])),
    ];
    let launches = launches();
    for (name, model) in &scenes {
        for &launch in &launches {
            table.rows::<f32>(name, model, launch);
        }
    }
    // f64 with its own control: Coulomb friction's kernels in f64.
    for (name, model) in &scenes {
        for &launch in &launches {
            table.rows::<f64>(name, model, launch);
        }
    }
    if !table.not_built.is_empty() {
        println!("\nNot built:");
        for why in &table.not_built {
            println!("- {why}");
        }
    }
    if let Some(dir) = &table.dump_dir {
        println!(
            "\nThe driver's internal representations, in {}: {} files",
            dir.display(),
            table.dumped.len()
        );
        for file in &table.dumped {
            println!("- {file}");
        }
    }
}
