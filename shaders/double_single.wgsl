// Double-single coordinates: a displacement is the unevaluated sum hi + lo
// of two f32 (vec2: x = hi, y = lo), so creep increments below one f32 ulp
// of u are kept. CPU twins: src/real.rs DoubleSingle::ds_add and ds_diff,
// the same operations in the same order.
//
// c.one is a runtime 1.0 from the uniform block. Multiplying the partial
// sums by it is exact but opaque to the compiler, so no driver can
// reassociate (s - hi) - s to -hi and cancel the error terms (gpuweb #2076).

// hi + lo + d, renormalised.
fn ds_add(a: vec2<f32>, d: f32) -> vec2<f32> {
    let s = (a.x + d) * c.one;
    let b = (s - a.x) * c.one;
    let err = (a.x - (s - b)) + (d - b);
    let lo = a.y + err;
    let hi = (s + lo) * c.one;
    return vec2<f32>(hi, lo - (hi - s) * c.one);
}

// a - b rounded to f32 once (exact leading difference for nearby values).
fn ds_diff(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return (a.x - b.x) + (a.y - b.y);
}
