//! The CPU twins of the WGSL kernels in `shaders/`, one file per kernel
//! with the same names and buffer layouts: bond and external forces
//! (`bulk_forces.wgsl`), the junction law (`junctions.wgsl`) and the
//! leapfrog step (`verlet`, in `common.wgsl`). The per-block friction
//! laws' twins (`shaders/laws/`) live with their laws in
//! `crate::model::friction`; `block_laws` is the engines' call of them. The CPU reference engine runs them phase by
//! phase, the fast CPU engine and the quasi-static solver reuse them: the
//! engines share these, never one another's code.

pub mod block_laws;
pub mod bulk_forces;
pub mod junctions;
pub mod verlet;
