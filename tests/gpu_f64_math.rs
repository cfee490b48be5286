//! The f64 shaders' own ln and e^x (`shaders/coord_f64.wgsl`: Vulkan has
//! no f64 log or exp) against Rust's, run on whatever adapter is present
//! (lavapipe in CI), over the whole f64 range: the junction RNG's 24-bit
//! uniforms, rate-and-state's ratios, and the extremes (subnormals, 2^±64
//! edges, the largest f64) that take `real_ln`'s exact pre-scaling branch.
//! Fails, never skips, without an adapter with f64.

#[path = "support/one_dispatch.rs"]
mod one_dispatch;

use one_dispatch::run_once;
use slipfront::engines::gpu::context::shared;
use slipfront::engines::gpu::shaders::file;
use wgpu::util::DeviceExt;

/// `real_ln` and `real_exp` of each input, computed on the adapter.
fn on_device(inputs: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let ctx = shared().expect("a GPU adapter (lavapipe in CI)");
    assert!(
        ctx.device.features().contains(wgpu::Features::SHADER_F64),
        "the adapter has no f64 shaders"
    );
    let source = format!(
        "alias real = f64;\nalias coord = f64;\nalias packed_coord = f64;\nalias force_sum = f64;\n{}\n{}",
        file("coord_f64").expect("coord_f64.wgsl"),
        r#"
@group(0) @binding(0) var<storage, read> inputs: array<f64>;
@group(0) @binding(1) var<storage, read_write> outputs: array<f64>;

@compute @workgroup_size(64)
fn ln_and_exp(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i < arrayLength(&inputs) {
        outputs[2u * i] = real_ln(inputs[i]);
        outputs[2u * i + 1u] = real_exp(clamp(inputs[i], -745.0, 709.0));
    }
}
"#
    );
    let input = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("inputs"),
            contents: bytemuck::cast_slice(inputs),
            usage: wgpu::BufferUsages::STORAGE,
        });
    let output = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("outputs"),
        size: (inputs.len() * 16) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let bytes = run_once(
        &ctx,
        source,
        "ln_and_exp",
        &[],
        &[(0, &input), (1, &output)],
        (inputs.len() as u32).div_ceil(64),
        &output,
    );
    let out: Vec<f64> = bytemuck::pod_collect_to_vec(&bytes);
    let ln = out.iter().step_by(2).copied().collect();
    let exp = out.iter().skip(1).step_by(2).copied().collect();
    (ln, exp)
}

/// Units in the last place between `a` and `b` (finite, same sign).
fn ulps(a: f64, b: f64) -> u64 {
    (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
}

#[test]
fn f64_ln_and_exp_match_rust_over_the_whole_range() {
    let mut inputs = vec![
        f64::from_bits(1), // the smallest subnormal
        1e-310,            // subnormal
        f64::MIN_POSITIVE, // the smallest normal
        1e-300,
        1e-100,
        2f64.powi(-64) * 0.999_999_999,
        2f64.powi(-64), // the pre-scaling branch's edges
        2f64.powi(64) * 0.999_999_999,
        2f64.powi(64),
        1e100,
        1e300,
        f64::MAX,
        0.5,
        std::f64::consts::FRAC_1_SQRT_2,
        std::f64::consts::FRAC_1_SQRT_2.next_down(),
        1.0,
        std::f64::consts::SQRT_2,
        std::f64::consts::SQRT_2.next_down(),
        2.0,
        -700.0,
        -80.0,
        -1.0,
        80.0,
        700.0,
    ];
    // The RNG's uniforms: (k + ½)/2^24, from its smallest up.
    for k in [
        0u32, 1, 2, 3, 1000, 123_456, 8_388_607, 8_388_608, 16_777_215,
    ] {
        inputs.push((k as f64 + 0.5) / 16_777_216.0);
    }
    // A sweep over 600 decades.
    for i in 0..600 {
        inputs.push(10f64.powf(-300.0 + i as f64 + 0.37));
    }
    // e^x from −700 to 700.
    for i in 0..200 {
        inputs.push(-700.0 + 7.0 * i as f64 + 0.123);
    }
    let (ln, exp) = on_device(&inputs);
    for (i, &x) in inputs.iter().enumerate() {
        if x > 0.0 {
            // Relative to max(|ln x|, 1): absolute near ln x = 0.
            let want = x.ln();
            let err = (ln[i] - want).abs() / want.abs().max(1.0);
            assert!(
                err < 4.0 * f64::EPSILON,
                "ln({x:e}) = {} on the device, {want} in Rust ({err:e})",
                ln[i]
            );
        }
        // e^x where it is a normal f64 (the kernels clamp to ±80).
        if (-708.0..709.0).contains(&x) {
            let want = x.exp();
            let u = ulps(exp[i], want);
            assert!(
                u <= 4,
                "exp({x}) = {} on the device, {want} in Rust ({u} ulp)",
                exp[i]
            );
        }
    }
    // Control: the comparison flags a wrong exponent (ln x + ln 2).
    let off = (ln[3] + std::f64::consts::LN_2 - inputs[3].ln()).abs() / inputs[3].ln().abs();
    assert!(off >= 4.0 * f64::EPSILON, "control");
}
