// f64 coordinates: with f64 arithmetic a displacement keeps creep
// increments by itself, so a coordinate is a plain f64 and these are the
// twins of src/model/real.rs `impl Coordinate<f64> for f64`. The same interface
// as the double-single functions of shaders/double_single.wgsl, which the
// kernels compile with in mixed precision.
// CPU twin: src/model/real.rs Coordinate, ForceSum (their f64 impls).
// import: (none)

fn coord_add(a: coord, d: real) -> coord {
    return a + d;
}

// A block's force sum: plain in f64 (CPU twin: ForceSum for f64).
// CPU twin: ForceSum::SPLITS_BONDS; f64: one term per bond (CPU twin: ForceSum::SPLITS_BONDS).
const SPLITS_BONDS: bool = false;

fn force_sum_zero() -> force_sum {
    return 0.0;
}

fn force_sum_add(a: force_sum, x: real) -> force_sum {
    return a + x;
}

fn force_sum_add_bond(a: force_sum, spring: real, damper: real) -> force_sum {
    return (a + spring) + damper;
}

fn force_sum_merge(a: force_sum, b: force_sum) -> force_sum {
    return a + b;
}

fn force_sum_value(a: force_sum) -> real {
    return a;
}

fn coord_diff(a: coord, b: coord) -> real {
    return a - b;
}

fn coord_value(a: coord) -> real {
    return a;
}

fn coord_rounded(a: coord) -> real {
    return a;
}

fn coord_f32(a: coord) -> f32 {
    return f32(a);
}

// An output row's two words: the value and 0 (its "lo").
fn coord_hi(a: coord) -> real {
    return a;
}

fn coord_lo(a: coord) -> real {
    return 0.0;
}

fn coord_pack(a: coord) -> packed_coord {
    return a;
}

fn coord_unpack(p: packed_coord) -> coord {
    return p;
}

// Vulkan's GLSL.std.450 has no f64 log or cos (only 16- and 32-bit), so
// the junction RNG's are computed here from +, ×, ÷, to within a few ulp
// of the CPU twin's libm (a slip time rounds to whole steps: only a draw
// within ~1e-15 of a half step could round otherwise).

// ln x for x > 0 (the RNG's 24-bit uniforms, rate-and-state's ratios):
// x = m·2^e with m in [√½, √2), ln m = 2 atanh(s), s = (m − 1)/(m + 1),
// |s| < 0.172. m and e are found without a loop: llvmpipe counts every
// pass of every loop against one budget a dispatch (a loop no junction
// enters still costs a pass there), and the persistent kernel's steps per
// dispatch are sized by that budget. (naga's f64 frexp gives an i64
// exponent, which needs SHADER_INT64; f32's gives an i32.)
fn ln_scale_up(me: vec2<real>, k: real, below: real, by: real) -> vec2<real> {
    return select(me, vec2<real>(me.x * by, me.y - k), me.x < below);
}

fn ln_scale_down(me: vec2<real>, k: real, at_least: real, by: real) -> vec2<real> {
    return select(me, vec2<real>(me.x * by, me.y + k), me.x >= at_least);
}

fn real_ln(x: real) -> real {
    var me = vec2<real>(x, 0.0);
    // Outside [2^-64, 2^64) (extreme rate-and-state ratios only): into it
    // by exact powers of two (2^-512 twice: subnormals reach 2^-1074).
    if x < 5.421010862427522e-20 || x >= 1.8446744073709552e19 {
        me = ln_scale_up(me, 512.0, 7.458340731200207e-155, 1.3407807929942597e154);
        me = ln_scale_up(me, 512.0, 7.458340731200207e-155, 1.3407807929942597e154);
        me = ln_scale_up(me, 256.0, 8.636168555094445e-78, 1.157920892373162e77);
        me = ln_scale_up(me, 128.0, 2.938735877055719e-39, 3.402823669209385e38);
        me = ln_scale_up(me, 64.0, 5.421010862427522e-20, 1.8446744073709552e19);
        me = ln_scale_down(me, 512.0, 1.3407807929942597e154, 7.458340731200207e-155);
        me = ln_scale_down(me, 256.0, 1.157920892373162e77, 8.636168555094445e-78);
        me = ln_scale_down(me, 128.0, 3.402823669209385e38, 2.938735877055719e-39);
        me = ln_scale_down(me, 64.0, 1.8446744073709552e19, 5.421010862427522e-20);
    }
    // The exponent of the value's f32 rounding (a normal f32 here), then m
    // exactly: f32 rounding moves it by 2^-24 at most, so m is in
    // [½ − 2^-25, 1), and one doubling puts it in [√½, √2).
    let e32 = frexp(f32(me.x)).exp;
    let half_to_one = ldexp(me.x, -e32);
    let low = half_to_one < 0.7071067811865476;
    let m = select(half_to_one, half_to_one * 2.0, low);
    let e = me.y + real(e32) - real(select(0, 1, low));
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    // 2 Σ s^(2k+1)/(2k+1), k ≤ 11: the next term is below 1e-19 of ln m.
    var p: real = 1.0 / 23.0;
    p = p * s2 + 1.0 / 21.0;
    p = p * s2 + 1.0 / 19.0;
    p = p * s2 + 1.0 / 17.0;
    p = p * s2 + 1.0 / 15.0;
    p = p * s2 + 1.0 / 13.0;
    p = p * s2 + 1.0 / 11.0;
    p = p * s2 + 1.0 / 9.0;
    p = p * s2 + 1.0 / 7.0;
    p = p * s2 + 1.0 / 5.0;
    p = p * s2 + 1.0 / 3.0;
    let ln_m = 2.0 * s + 2.0 * s * (s2 * p);
    // ln 2 = LN2_HI + LN2_LO, LN2_HI with 32 significant bits: e·LN2_HI is
    // exact for |e| < 2^21.
    let ln2_hi: real = 6.93147180369123816490e-01;
    let ln2_lo: real = 1.90821492927058770002e-10;
    return e * ln2_hi + (ln_m + e * ln2_lo);
}

// e^x (rate-and-state friction): x = n·ln 2 + r with ln 2 in two parts
// (n·LN2_HI exact for |n| < 2^21), |r| ≤ ln2/2, e^r by its Taylor series
// to r^13 (the next term is below 5e-18), times 2^n by ldexp (exact where
// the result is normal; no loop, as in real_ln); 0 below −745 and held at
// e^709 above (the f64 range).
fn real_exp(x: real) -> real {
    if x < -745.0 {
        return 0.0;
    }
    let xc = min(x, 709.0);
    let n = floor(xc * 1.4426950408889634 + 0.5);
    let ln2_hi: real = 6.93147180369123816490e-01;
    let ln2_lo: real = 1.90821492927058770002e-10;
    let r = (xc - n * ln2_hi) - n * ln2_lo;
    var p: real = 1.0 / 6227020800.0;
    p = p * r + 1.0 / 479001600.0;
    p = p * r + 1.0 / 39916800.0;
    p = p * r + 1.0 / 3628800.0;
    p = p * r + 1.0 / 362880.0;
    p = p * r + 1.0 / 40320.0;
    p = p * r + 1.0 / 5040.0;
    p = p * r + 1.0 / 720.0;
    p = p * r + 1.0 / 120.0;
    p = p * r + 1.0 / 24.0;
    p = p * r + 1.0 / 6.0;
    p = p * r + 0.5;
    p = p * r + 1.0;
    let y = p * r + 1.0;
    return ldexp(y, i32(n));
}

// sin r and cos r for |r| ≤ π/4 (Taylor series to r^19 and r^18).
fn sin_small(r: real) -> real {
    let r2 = r * r;
    var p: real = -1.0 / 121645100408832000.0;
    p = p * r2 + 1.0 / 355687428096000.0;
    p = p * r2 - 1.0 / 1307674368000.0;
    p = p * r2 + 1.0 / 6227020800.0;
    p = p * r2 - 1.0 / 39916800.0;
    p = p * r2 + 1.0 / 362880.0;
    p = p * r2 - 1.0 / 5040.0;
    p = p * r2 + 1.0 / 120.0;
    p = p * r2 - 1.0 / 6.0;
    return r + r * (r2 * p);
}

fn cos_small(r: real) -> real {
    let r2 = r * r;
    var p: real = -1.0 / 6402373705728000.0;
    p = p * r2 + 1.0 / 20922789888000.0;
    p = p * r2 - 1.0 / 87178291200.0;
    p = p * r2 + 1.0 / 479001600.0;
    p = p * r2 - 1.0 / 3628800.0;
    p = p * r2 + 1.0 / 40320.0;
    p = p * r2 - 1.0 / 720.0;
    p = p * r2 + 1.0 / 24.0;
    return 1.0 - 0.5 * r2 + r2 * (r2 * p);
}

// cos x for 0 ≤ x ≤ 2π (the RNG's 2π·u): x = q·π/2 + r with π/2 in two
// parts (q·PIO2_HI exact for q ≤ 4), |r| ≤ π/4.
fn real_cos(x: real) -> real {
    let pio2_hi: real = 1.57079632673412561417e+00;
    let pio2_lo: real = 6.07710050650619224932e-11;
    let q = floor(x * 0.6366197723675814 + 0.5);
    let r = (x - q * pio2_hi) - q * pio2_lo;
    switch u32(q) & 3u {
        case 0u: {
            return cos_small(r);
        }
        case 1u: {
            return -sin_small(r);
        }
        case 2u: {
            return -cos_small(r);
        }
        default: {
            return sin_small(r);
        }
    }
}
