//! What the driver's compiler made of each kernel: the registers a thread
//! needs, spills, code size, as the driver itself reports them
//! (VK_KHR_pipeline_executable_properties). wgpu neither enables that
//! extension nor says how many registers a pipeline got, and the
//! registers a thread needs decide how many workgroups an SM holds at
//! once: whether two Table S1 scenes share an SM or wait for each other
//! (docs/gpu-kernels.md, "What limits an ensemble").
//!
//! The kernel is compiled a second time, outside wgpu, from the same
//! source and override constants the engine gave wgpu
//! (`GpuEngine::kernel_sources`), into SPIR-V written with wgpu's options
//! (`gpu::spirv`), on a device of its own (`vulkan`). NVIDIA's driver reports
//! "Register Count"; Mesa's RADV reports "VGPRs" and "Subgroups per SIMD",
//! also on its null device (`RADV_FORCE_FAMILY`, no AMD GPU needed);
//! lavapipe reports nothing.

mod vulkan;

pub use vulkan::{DeviceChoice, StatsDevice};

/// One statistic's value, in the format the driver gave it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StatValue {
    Bool(bool),
    Int(i64),
    Uint(u64),
    Float(f64),
}

impl StatValue {
    /// The value as a count (None for a flag or a fraction).
    pub fn count(self) -> Option<u64> {
        match self {
            StatValue::Int(v) => u64::try_from(v).ok(),
            StatValue::Uint(v) => Some(v),
            StatValue::Bool(_) | StatValue::Float(_) => None,
        }
    }
}

impl std::fmt::Display for StatValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StatValue::Bool(b) => write!(f, "{b}"),
            StatValue::Int(v) => write!(f, "{v}"),
            StatValue::Uint(v) => write!(f, "{v}"),
            StatValue::Float(v) => write!(f, "{v}"),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Statistic {
    pub name: String,
    pub description: String,
    pub value: StatValue,
}

/// One of the driver's internal forms of an executable (its IR, its
/// machine code), where it gives them (`StatsDevice::capture_representations`):
/// the instructions a loop of a kernel issues, on the hardware itself.
#[derive(Debug, Clone, PartialEq)]
pub struct Representation {
    pub name: String,
    pub description: String,
    /// Text (disassembly, IR) or the driver's binary.
    pub is_text: bool,
    pub data: Vec<u8>,
}

/// One executable the driver made of a pipeline, and its statistics.
#[derive(Debug, Clone, PartialEq)]
pub struct Executable {
    pub name: String,
    pub description: String,
    /// The subgroup size it runs at (0 where the driver does not say).
    pub subgroup_size: u32,
    pub statistics: Vec<Statistic>,
    /// Empty unless asked for (and given by the driver).
    pub representations: Vec<Representation>,
}

/// The statistics' names for the registers a thread holds: NVIDIA's, then
/// AMD's vector registers (RADV and AMD's own driver).
const REGISTER_NAMES: [&str; 3] = ["Register Count", "VGPRs", "numUsedVgprs"];

impl Executable {
    /// The count of statistic `name` (case as the driver spells it).
    pub fn count(&self, name: &str) -> Option<u64> {
        self.statistics
            .iter()
            .find(|s| s.name == name)
            .and_then(|s| s.value.count())
    }

    /// The registers a thread holds, where the driver reports them.
    pub fn registers(&self) -> Option<u64> {
        REGISTER_NAMES.iter().find_map(|n| self.count(n))
    }
}

/// NVIDIA's PCI vendor id.
pub const NVIDIA: u32 = 0x10de;

/// What bounds the workgroups an NVIDIA SM of compute capability 8.0–9.0
/// (A100, H100, H200) holds at once: 65,536 32-bit registers in four
/// quarters of 16,384, a warp's registers allocated in units of 256 (a
/// thread's rounded up to a multiple of 8) within one quarter, at most
/// 2,048 threads and 32 workgroups.
pub fn nvidia_workgroups_per_sm(registers_per_thread: u64, threads: u64) -> u64 {
    if threads == 0 || registers_per_thread == 0 {
        return 0;
    }
    let per_warp = registers_per_thread.div_ceil(8) * 8 * 32;
    let warps_by_registers = 4 * (16_384 / per_warp);
    let warps = threads.div_ceil(32);
    let by_registers = warps_by_registers / warps;
    let by_threads = 2_048 / (warps * 32);
    by_registers.min(by_threads).min(32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The occupancy bound against CUDA's occupancy calculator for
    /// compute capability 9.0 (its register rows).
    #[test]
    fn workgroups_an_sm_holds_by_registers() {
        // 256 threads: two workgroups up to 128 registers, one above.
        assert_eq!(nvidia_workgroups_per_sm(128, 256), 2);
        assert_eq!(nvidia_workgroups_per_sm(129, 256), 1);
        assert_eq!(nvidia_workgroups_per_sm(64, 256), 4);
        assert_eq!(nvidia_workgroups_per_sm(32, 256), 8);
        // 1024 threads fit only at 64 registers or fewer.
        assert_eq!(nvidia_workgroups_per_sm(64, 1024), 1);
        assert_eq!(nvidia_workgroups_per_sm(65, 1024), 0);
        // 512 threads at 40 registers (rounded to 40): 4 × 16,384 / 1,280
        // = 48 warps, 3 workgroups of 16 warps.
        assert_eq!(nvidia_workgroups_per_sm(40, 512), 3);
        // The thread limit: 64-thread workgroups at 16 registers, 32.
        assert_eq!(nvidia_workgroups_per_sm(16, 64), 32);
        assert_eq!(nvidia_workgroups_per_sm(0, 256), 0);
    }

    #[test]
    fn registers_are_read_from_either_vendors_name() {
        let stat = |name: &str, value| Statistic {
            name: name.into(),
            description: String::new(),
            value,
        };
        let nv = Executable {
            name: "compute".into(),
            description: String::new(),
            subgroup_size: 32,
            statistics: vec![
                stat("Binary Size", StatValue::Uint(9000)),
                stat("Register Count", StatValue::Uint(96)),
            ],
            representations: Vec::new(),
        };
        assert_eq!(nv.registers(), Some(96));
        let amd = Executable {
            statistics: vec![
                stat("SGPRs", StatValue::Uint(40)),
                stat("VGPRs", StatValue::Int(72)),
                stat("Spilled VGPRs", StatValue::Uint(0)),
            ],
            ..nv.clone()
        };
        assert_eq!(amd.registers(), Some(72));
        let none = Executable {
            statistics: vec![stat("Uses barriers", StatValue::Bool(true))],
            ..nv
        };
        assert_eq!(none.registers(), None);
    }
}
