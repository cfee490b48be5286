// Double-single coordinates: a displacement is the unevaluated sum hi + lo
// of two f32 (vec2: x = hi, y = lo), so creep increments below one f32 ulp
// of u are kept. CPU twin: src/model/real.rs DoubleSingle::ds_add, DoubleSingle::ds_diff
// (the same operations in the same order), CompensatedSum.
//
// c.one is a runtime 1.0 from the scene's constants. Multiplying the partial
// sums by it is exact but opaque to the compiler, so no driver can
// reassociate (s - hi) - s to -hi and cancel the error terms (gpuweb #2076).
// And every term a two-sum adds passes through `opaque` first. The terms
// are mostly products (k·(a − r), q·r0, dt·v), and SPIR-V lets a driver
// fuse a product into the add that takes it (an FMA: naga marks nothing
// NoContraction). A fused first add rounds the exact product while the
// error term is made from the rounded one, so the pair no longer holds the
// sum; and whether a driver fuses depends on the code around the add, so
// kernels computing the same block parted (on lavapipe, where a junction
// sum fell on a rounding tie). Guarding the product with c.one does not
// stop it: a compiler may factor x·one + y·one into (x + y)·one.
//
// Both guards are for the modules wgpu writes. Where the engine writes a
// module's SPIR-V itself (KernelBuild::strict_arithmetic) it sets
// FUSION_GUARDS false and decorates every floating-point operation
// NoContraction instead (spirv::forbid_contraction), which forbids the
// driver both fusing and regrouping, everywhere, in fewer instructions.
// import: scene

override FUSION_GUARDS: bool = true;

// x times the run-time 1.0 where the guards are compiled in.
fn fenced(x: f32) -> f32 {
    return select(x, x * c.one, FUSION_GUARDS);
}

// x, its bits passed through an integer operation whose operand is zero
// only at run time (c.one's bits less 1.0's): no compiler can fuse or
// regroup the arithmetic that made x with the arithmetic that uses it.
fn opaque(x: f32) -> f32 {
    let hidden = bitcast<f32>(bitcast<u32>(x) ^ (bitcast<u32>(c.one) ^ 0x3f800000u));
    return select(x, hidden, FUSION_GUARDS);
}

// hi + lo + d, renormalised.
fn ds_add(a: vec2<f32>, increment: f32) -> vec2<f32> {
    let d = opaque(increment);
    let s = fenced(a.x + d);
    let b = fenced(s - a.x);
    let err = (a.x - (s - b)) + (d - b);
    let lo = a.y + err;
    let hi = fenced(s + lo);
    return vec2<f32>(hi, lo - fenced(hi - s));
}

// a - b rounded to f32 once (exact leading difference for nearby values).
fn ds_diff(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return (a.x - b.x) + (a.y - b.y);
}

// The coordinate interface the kernels use (shaders/coord_f64.wgsl is the
// f64 one): the prelude declares `alias coord = vec2<f32>;`, and packed
// coordinates (junction anchors, array<f32, 2>: 4-byte aligned, so a
// JunctionSpring stays 12 bytes).
fn coord_add(a: coord, d: real) -> coord {
    return ds_add(a, d);
}

// The forces on one block are summed with their rounding errors kept
// apart (x = sum, y = error; Knuth's two-sum per term): a block's terms
// nearly cancel, and an f32 running sum broke action = reaction at the
// rounding level. CPU twin: src/model/real.rs CompensatedSum::add and value.
// CPU twin: ForceSum::SPLITS_BONDS; mixed f32: bonds split into q·r0 + q·du (shaders/bulk_forces.wgsl).
const SPLITS_BONDS: bool = true;

fn force_sum_zero() -> force_sum {
    return vec2<f32>(0.0, 0.0);
}

fn force_sum_add(a: force_sum, term: f32) -> force_sum {
    let x = opaque(term);
    let t = fenced(a.x + x);
    let b = fenced(t - a.x);
    let e = (a.x - (t - b)) + (x - b);
    return vec2<f32>(t, a.y + e);
}

// One bond's spring and dashpot terms, the rotation part of a split bond
// (q·du + dashpot: a strain's fraction of its q·r0), added to the error
// word in plain f32: only the large q·r0 terms, which cancel across a
// block, need the two-sum (CompensatedSum::add_bond). Their f32 sum is
// antisymmetric like the terms, so action still equals reaction. Both
// are products, hence `opaque` (above).
fn force_sum_add_bond(a: force_sum, spring: f32, damper: f32) -> force_sum {
    return vec2<f32>(a.x, a.y + (opaque(spring) + opaque(damper)));
}

// Two partial sums joined (a block's junction lanes): the sums two-summed,
// both error terms kept. CPU twin: CompensatedSum::merge.
fn force_sum_merge(a: force_sum, b: force_sum) -> force_sum {
    let joined = force_sum_add(a, b.x);
    return vec2<f32>(joined.x, joined.y + b.y);
}

fn force_sum_value(a: force_sum) -> f32 {
    return a.x + a.y;
}

fn coord_diff(a: coord, b: coord) -> real {
    return ds_diff(a, b);
}

// The value rounded to f32 as the CPU twin's Coordinate::value: hi.
fn coord_value(a: coord) -> real {
    return a.x;
}

// hi + lo rounded once.
fn coord_rounded(a: coord) -> real {
    return a.x + a.y;
}

fn coord_f32(a: coord) -> f32 {
    return a.x + a.y;
}

// The two words an output row stores (hi, lo).
fn coord_hi(a: coord) -> real {
    return a.x;
}

fn coord_lo(a: coord) -> real {
    return a.y;
}

fn coord_pack(a: coord) -> packed_coord {
    return packed_coord(a.x, a.y);
}

fn coord_unpack(p: packed_coord) -> coord {
    return vec2<f32>(p[0], p[1]);
}

// The junction RNG's transcendental functions (f32 has them built in).
fn real_ln(x: real) -> real {
    return log(x);
}

fn real_cos(x: real) -> real {
    return cos(x);
}

// e^x (rate-and-state friction).
fn real_exp(x: real) -> real {
    return exp(x);
}
