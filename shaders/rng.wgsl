// Counter-based junction RNG: the same functions as src/model/rng.rs, line for line.
// CPU twin: src/model/rng.rs pcg_hash, draw_key, uniform_pair, standard_normal, slip_steps
// import: coordinates

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn draw_key(seed: u32, block: u32, junction: u32, count: u32) -> u32 {
    return pcg_hash(count ^ pcg_hash(junction ^ pcg_hash(block ^ pcg_hash(seed))));
}

fn unit_from_bits(bits: u32) -> real {
    return (real(bits >> 8u) + 1.0) * (1.0 / 16777216.0);
}

fn standard_normal(seed: u32, block: u32, junction: u32, count: u32) -> real {
    let a = pcg_hash(draw_key(seed, block, junction, count));
    let b = pcg_hash(a);
    let u1 = unit_from_bits(a);
    let u2 = unit_from_bits(b);
    return sqrt(-2.0 * real_ln(u1)) * real_cos(6.283185307179586 * u2);
}

fn slip_steps(seed: u32, block: u32, junction: u32, count: u32, mean_steps: real, std_steps: real) -> u32 {
    let z = standard_normal(seed, block, junction, count);
    // floor(x + 0.5): Rust's round() for the non-negative values used here.
    let steps = floor(max(mean_steps + std_steps * z, 0.0) + 0.5);
    return max(u32(steps), 1u);
}
