// Dieterich–Ruina rate-and-state friction on interface block ix over one
// step, implicit in the velocity (see the twin for why and how); returns
// (friction, normal force) and updates θ and the slide pair. Constants:
// c.law0..law6 = (a, b, μ0, V0, Dc, evolution 0 aging / 1 slip, slip
// velocity). CPU twin: src/model/friction/rate_state/twin.rs rate_state, state_increment, phi, solve_friction_level.
// import: common, coordinates, scene, state

const RS_MAX_ITERATIONS: u32 = 200u;

// e^x with the argument held in [−80, 80]: no overflow in f32 (the solve
// only needs the sign of k far from its root).
fn rs_exp(x: real) -> real {
    return real_exp(clamp(x, -80.0, 80.0));
}

// (1 − e^(−z))/z, by its series for |z| < 0.01 (twin: phi).
fn rs_phi(z: real) -> real {
    if abs(z) < 1e-2 {
        var p: real = -1.0 / 720.0;
        p = p * z + 1.0 / 120.0;
        p = p * z - 1.0 / 24.0;
        p = p * z + 1.0 / 6.0;
        p = p * z - 1.0 / 2.0;
        return p * z + 1.0;
    }
    return (1.0 - real_exp(-z)) / z;
}

// The change of θ over dt at constant slip speed (twin: state_increment).
fn rs_state_increment(theta: real, speed: real, dt: real) -> real {
    let x = speed * dt / c.law4;
    if c.law5 == 0.0 {
        return dt * rs_phi(x) * (1.0 - theta * speed / c.law4);
    }
    if speed > 0.0 {
        let y = -(x * rs_phi(x)) * real_ln(theta * speed / c.law4);
        return theta * (y * rs_phi(-y));
    }
    return 0.0;
}

// k(μ) = V(μ) − X + κμ, V(μ) = V0 (e^((μ−ψ)/a) − e^(−(μ+ψ)/a)).
fn rs_residual(mu: real, a: real, v0: real, psi: real, x: real, kappa: real) -> real {
    return v0 * (rs_exp((mu - psi) / a) - rs_exp(-(mu + psi) / a)) - x + kappa * mu;
}

// The step's friction level: the root of k on [0, X/κ] (twin:
// solve_friction_level).
fn rs_solve(a: real, v0: real, psi: real, x: real, kappa: real) -> real {
    var hi = x / kappa;
    let guess = psi + a * real_ln(2.0 * x / v0 + 1.0);
    if guess > 0.0 && guess < hi && rs_residual(guess, a, v0, psi, x, kappa) >= 0.0 {
        hi = guess;
    }
    var lo: real = 0.0;
    var mu = hi;
    let tol = REAL_EPSILON * 8.0;
    for (var i = 0u; i < RS_MAX_ITERATIONS; i++) {
        let kv = rs_residual(mu, a, v0, psi, x, kappa);
        if kv == 0.0 {
            break;
        }
        if kv > 0.0 {
            hi = mu;
        } else {
            lo = mu;
        }
        let slope = v0 / a * (rs_exp((mu - psi) / a) + rs_exp(-(mu + psi) / a)) + kappa;
        var next = mu - kv / slope;
        if !(next > lo && next < hi) {
            next = (lo + hi) * 0.5;
        }
        let done = abs(next - mu) <= tol * (abs(mu) + a);
        mu = next;
        if done || hi - lo <= tol * (hi + a) {
            break;
        }
    }
    return mu;
}

fn rate_state(ix: u32, other: real, ld: Loads) -> vec2<real> {
    let v = load_vel(ix);
    let normal = foundation_normal(coord_value(load_disp(ix).z));
    let at = interface_base() + ix;
    let theta_at = coord_unpack(law_state[at]);
    let theta = coord_value(theta_at);
    var state = slide[at];
    if ld.preparing {
        // The interface holds while the normal load is applied; its
        // contacts age at rest.
        law_state[at] = coord_pack(coord_add(theta_at, rs_state_increment(theta, 0.0, c.dt)));
        slide[at] = vec2<i32>(0, state.y);
        return vec2<real>(-other - c.mass * v.x / c.dt, normal);
    }
    let free = v.x + c.dt * other / c.mass;
    let x = abs(free);
    let kappa = c.dt * normal / c.mass;
    var mu: real = 0.0;
    var speed = x;
    if x != 0.0 && kappa > 0.0 {
        let psi = c.law2 + c.law1 * real_ln(c.law3 * theta / c.law4);
        mu = rs_solve(c.law0, c.law3, psi, x, kappa);
        speed = max(x - kappa * mu, 0.0);
    }
    law_state[at] = coord_pack(coord_add(theta_at, rs_state_increment(theta, speed, c.dt)));
    var dir = 0;
    if speed >= c.law6 {
        dir = select(-1, 1, free > 0.0);
    }
    if state.x == 0 && dir != 0 {
        state.y = state.y + 1;
    }
    slide[at] = vec2<i32>(dir, state.y);
    let sign = select(real(-1.0), real(1.0), free > 0.0);
    return vec2<real>(-sign * max(normal, 0.0) * mu, normal);
}
