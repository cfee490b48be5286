// Shared by both kernels: the bindings other than the block state, the
// force laws every phase uses, and the loads of a step. The structs and
// constants come from src/engines/gpu/layout.rs (prepended as a prelude).
// CPU twin: src/engines/step_params.rs step_params (the loads of a step).
// import: scene, coordinates

// The run constants `c` and the batch `batch` of the scene a thread steps
// are declared by the scene snippet (scene.wgsl), with the offsets of that
// scene in every buffer.
// Force on each block from everything but friction, at the state the step
// starts from.
@group(0) @binding(5) var<storage, read_write> force: array<vec2<real>>;
@group(0) @binding(6) var<storage, read> flags: array<u32>;
// (friction along x, normal force) per interface block.
@group(0) @binding(7) var<storage, read_write> contact: array<vec2<real>>;
// Index ix * Ns + j.
@group(0) @binding(8) var<storage, read_write> junction_spring: array<JunctionSpring>;
// (slip steps left or PINNED, rupture count) per junction.
@group(0) @binding(9) var<storage, read_write> junction_state: array<vec2<u32>>;
// Per interface block, the sums of its junctions while none of them
// changes (junctions.wgsl, junction_block); zeroed records are empty.
@group(0) @binding(23) var<storage, read_write> junction_cache: array<JunctionCache>;
// (sliding direction 0/±1, stick → slip count) per interface block.
@group(0) @binding(10) var<storage, read_write> slide: array<vec2<i32>>;
// The friction law's own state, its block_state_words per interface block
// (crate::model::friction::Law): θ of rate-and-state. Coordinates, as
// displacements are: tiny increments (aging at rest) are kept.
@group(0) @binding(17) var<storage, read_write> law_state: array<packed_coord>;
// Each scene's GpuStatus: its first blow-up (flag, step, block, ux, uz,
// vx, vz), then the kernels' counters (STATUS_WORDS words per scene).
@group(0) @binding(11) var<storage, read_write> status: array<atomic<u32>>;

// Junction k of the junction arrays: the only way the junction phase
// reads and writes them (junction_first says where a block's are).
fn junction_state_at(k: u32) -> vec2<u32> {
    return junction_state[k];
}

fn junction_spring_at(k: u32) -> JunctionSpring {
    return junction_spring[k];
}

fn set_junction_state(k: u32, state: vec2<u32>) {
    junction_state[k] = state;
}

fn set_junction_spring(k: u32, spring: JunctionSpring) {
    junction_spring[k] = spring;
}

// A scene that blew up is left as it is (its status keeps the first
// blow-up) while the others go on.
fn scene_stopped() -> bool {
    return atomicLoad(&status[status_base() + STATUS_FLAG]) != 0u;
}
// The step offset of this dispatch in its batch: a dynamic offset into a
// fixed table, or, where the adapter has immediates, an immediate (the
// declaration below rewritten to the immediate address space) that the
// host sets before each dispatch (compile.rs, KernelBuild::step_immediate).
// The batch (binding 1) is storage, not uniform: lavapipe specialises
// shaders on uniform contents and would recompile.
@group(1) @binding(0) var<storage, read> step_offset: u32;

// The friction law compiled in: one of the LAW_* constants, which the
// prelude generates from layout::KernelLaw.
override FRICTION_LAW: u32 = 1u;

// Normal force the foundation carries under an interface block
// (CPU twin: cpu::junctions::foundation_normal).
fn foundation_normal(uz: real) -> real {
    return c.k_foundation * max(-uz, 0.0);
}

// The loads of step batch.first + i (CPU twin: step_params::step_params).
// While driving, time and drive target are those of the batch's anchor
// (a step that is a multiple of DRIVE_ANCHOR_STEPS into driving) plus
// batch.anchor_offset + i steps.
struct Loads {
    preparing: bool,
    normal_total: real,
    top_tangential_total: real,
    absolute_eta: real,
    interface_shear_total: real,
    strip_shear_total: real,
    top_velocity: real,
    drive_target: coord,
}

fn loads_at(i: u32) -> Loads {
    var ramp: real = 1.0;
    if batch.ramping != 0u {
        ramp = real(batch.first_step + i) * c.inv_ramp_steps;
    }
    let preparing = batch.preparing != 0u;
    // Steps from the batch's anchor (< 4096): the drive's time and target at
    // a step do not depend on where batches begin.
    let fi = real(batch.anchor_offset + i);
    var ld: Loads;
    ld.preparing = preparing;
    ld.normal_total = c.normal_force * ramp;
    ld.top_tangential_total = c.top_prestress_force * ramp;
    ld.absolute_eta = select(0.0, c.relax_eta, batch.relaxing != 0u);
    ld.interface_shear_total = 0.0;
    ld.strip_shear_total = 0.0;
    ld.top_velocity = 0.0;
    ld.drive_target = batch.drive_target;
    if !preparing {
        let drive_time = batch.drive_time + fi * c.dt;
        ld.top_tangential_total = ld.top_tangential_total + c.top_force_rate * drive_time;
        ld.top_velocity = c.drive_velocity;
        ld.absolute_eta = c.absolute_eta;
        ld.interface_shear_total = c.interface_shear_force;
        ld.strip_shear_total = c.strip_shear_force;
        // fi·hi is exact (hi has 12 significant bits, fi < 4096).
        ld.drive_target = coord_add(coord_add(ld.drive_target, fi * c.drive_step_hi), fi * c.drive_step_lo);
    }
    return ld;
}

// Records the first blow-up (non-finite or faster than c_p); the status
// words hold real values whatever the precision.
fn report_blow_up(i: u32, step: u32, u: Disp, v: vec2<real>) {
    let s = status_base();
    if atomicAdd(&status[s + STATUS_FLAG], 1u) == 0u {
        atomicStore(&status[s + STATUS_STEP], step);
        atomicStore(&status[s + STATUS_BLOCK], i);
        atomicStore(&status[s + STATUS_UX], bitcast<u32>(coord_f32(u.x)));
        atomicStore(&status[s + STATUS_UZ], bitcast<u32>(coord_f32(u.z)));
        atomicStore(&status[s + STATUS_VX], bitcast<u32>(f32(v.x)));
        atomicStore(&status[s + STATUS_VZ], bitcast<u32>(f32(v.y)));
    }
}

// A thread's items first, first + stride, ... of a grid `width` items wide
// (item k at column k mod width, row k / width), walked by column and row
// with no division per item: dividing by a width known only at run time
// costs a GPU about twenty instructions, a few per block-step in the tiled
// kernel's loops. The kernels' loops over blocks, lanes and tile columns.
struct GridWalk {
    column: u32,
    row: u32,
    step_columns: u32,
    step_rows: u32,
    width: u32,
}

fn grid_walk(first: u32, stride: u32, width: u32) -> GridWalk {
    return GridWalk(first % width, first / width, stride % width, stride / width, width);
}

fn grid_walk_next(w: ptr<function, GridWalk>) {
    (*w).column += (*w).step_columns;
    (*w).row += (*w).step_rows;
    if (*w).column >= (*w).width {
        (*w).column -= (*w).width;
        (*w).row += 1u;
    }
}

// The blocks of columns a ..< b (all rows) split for the force phase: the
// inner ones (column in 1 ..= nx − 2, row in 1 ..= nz − 2: every neighbour
// present), then the rim, so that a subgroup's threads take the path
// without bounds together (inner_bulk_force). A lattice under three
// blocks wide or high is all rim.
struct BlockSpan {
    // Inner columns first ..< end, rows 1 ..= nz − 2.
    inner_first: u32,
    inner_columns: u32,
    inner_count: u32,
    a: u32,
    b: u32,
}

fn block_span(a: u32, b: u32) -> BlockSpan {
    let first = max(a, 1u);
    let end = min(b, c.nx - 1u);
    if c.nx < 3u || c.nz < 3u || end <= first {
        return BlockSpan(first, 0u, 0u, a, b);
    }
    return BlockSpan(first, end - first, (end - first) * (c.nz - 2u), a, b);
}

// (column, row) of the span's rim block r (r < its blocks − inner_count):
// the bottom row, the top row, then column 0 and column nx − 1 between
// them where the span holds them.
fn span_rim_block(s: BlockSpan, r: u32) -> vec2<u32> {
    let cols = s.b - s.a;
    if c.nx < 3u || c.nz < 3u {
        return vec2<u32>(s.a + r % cols, r / cols);
    }
    if r < cols {
        return vec2<u32>(s.a + r, 0u);
    }
    if r < 2u * cols {
        return vec2<u32>(s.a + r - cols, c.nz - 1u);
    }
    let side = r - 2u * cols;
    let inner_rows = c.nz - 2u;
    if s.a == 0u && side < inner_rows {
        return vec2<u32>(0u, side + 1u);
    }
    return vec2<u32>(c.nx - 1u, side - select(0u, inner_rows, s.a == 0u) + 1u);
}
