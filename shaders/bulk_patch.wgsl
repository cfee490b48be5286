// The bulk forces of a 2×2 patch of blocks by one thread, each bond
// inside the patch computed once: of a patch's 32 stencil entries, 12 are
// its 6 inner bonds seen from both ends, so a thread does 26 bonds' work
// where four threads of bulk_force do 32, and reads 24 blocks' state
// where they read 36 (16, where a driver merges the ring's repeated reads). A bond seen from its other end adds exactly its terms
// negated (bulk_forces.wgsl: BondTerms), and every block still adds its
// bonds in stencil order, so each force has bulk_force's bits.
// The patch at column x0 and row z0 holds blocks
//   a (x0, z0), b (x0 + 1, z0), c (x0, z0 + 1), d (x0 + 1, z0 + 1),
// those of columns before x_end (c.nx, or where the tiled kernel's
// step stops) and rows of the lattice: at an odd count's last column or
// row, half a patch.
// Written out for the stencil's order (1,0), (−1,0), (0,1), (0,−1),
// (1,1), (−1,1), (1,−1), (−1,−1) (src/model/lattice.rs STENCIL; its test
// `the_bond_patch_shader_assumes_the_stencils_order` holds it there).
// CPU twin: src/engines/kernels/bulk_forces.rs bulk_force_patch.
// import: bulk_forces, common, coordinates, scene, state

// The patch's forces, by block (a block outside the lattice: zero).
struct PatchForces {
    a: vec2<real>,
    b: vec2<real>,
    c: vec2<real>,
    d: vec2<real>,
}

fn bulk_force_patch(x0: u32, z0: u32, x_end: u32, ld: Loads) -> PatchForces {
    let has_b = x0 + 1u < x_end;
    let has_c = z0 + 1u < c.nz;
    let has_d = has_b && has_c;
    let ia = z0 * c.nx + x0;
    let ib = ia + 1u;
    let ic = ia + c.nx;
    let id = ic + 1u;
    let xa = i32(x0);
    let za = i32(z0);
    let ua = load_disp_at(ia, x0, z0);
    let va = load_vel_at(ia, x0, z0);
    var ub: Disp;
    var vb = vec2<real>(0.0, 0.0);
    var uc: Disp;
    var vc = vec2<real>(0.0, 0.0);
    var ud: Disp;
    var vd = vec2<real>(0.0, 0.0);
    if has_b {
        ub = load_disp_at(ib, x0 + 1u, z0);
        vb = load_vel_at(ib, x0 + 1u, z0);
    }
    if has_c {
        uc = load_disp_at(ic, x0, z0 + 1u);
        vc = load_vel_at(ic, x0, z0 + 1u);
    }
    if has_d {
        ud = load_disp_at(id, x0 + 1u, z0 + 1u);
        vd = load_vel_at(id, x0 + 1u, z0 + 1u);
    }
    // The inner bonds, each computed by the first of its blocks in patch
    // order and added negated by the second.
    var ab: BondTerms;
    var ac: BondTerms;
    var ad: BondTerms;
    var bc: BondTerms;
    var bd: BondTerms;
    var cd: BondTerms;
    var out: PatchForces;

    // Block a: b, c and d are its inner neighbours.
    var fx = force_sum_zero();
    var fz = force_sum_zero();
    if has_b {
        ab = bond_terms(ua, va, ub, vb, STENCIL[0], STENCIL_LENGTH[0], STENCIL_STIFFNESS[0]);
        add_bond_terms(ab, STENCIL[0], &fx, &fz);
    }
    add_bond(xa, za, ua, va, STENCIL[1], STENCIL_LENGTH[1], STENCIL_STIFFNESS[1], &fx, &fz);
    if has_c {
        ac = bond_terms(ua, va, uc, vc, STENCIL[2], STENCIL_LENGTH[2], STENCIL_STIFFNESS[2]);
        add_bond_terms(ac, STENCIL[2], &fx, &fz);
    }
    add_bond(xa, za, ua, va, STENCIL[3], STENCIL_LENGTH[3], STENCIL_STIFFNESS[3], &fx, &fz);
    if has_d {
        ad = bond_terms(ua, va, ud, vd, STENCIL[4], STENCIL_LENGTH[4], STENCIL_STIFFNESS[4]);
        add_bond_terms(ad, STENCIL[4], &fx, &fz);
    }
    add_bond(xa, za, ua, va, STENCIL[5], STENCIL_LENGTH[5], STENCIL_STIFFNESS[5], &fx, &fz);
    add_bond(xa, za, ua, va, STENCIL[6], STENCIL_LENGTH[6], STENCIL_STIFFNESS[6], &fx, &fz);
    add_bond(xa, za, ua, va, STENCIL[7], STENCIL_LENGTH[7], STENCIL_STIFFNESS[7], &fx, &fz);
    out.a = external_loads(ia, x0, ua, va, fx, fz, ld);

    // Block b: a to its left, d above, c up to the left.
    if has_b {
        let xb = xa + 1;
        fx = force_sum_zero();
        fz = force_sum_zero();
        add_bond(xb, za, ub, vb, STENCIL[0], STENCIL_LENGTH[0], STENCIL_STIFFNESS[0], &fx, &fz);
        add_bond_terms(bond_terms_negated(ab), STENCIL[1], &fx, &fz);
        if has_d {
            bd = bond_terms(ub, vb, ud, vd, STENCIL[2], STENCIL_LENGTH[2], STENCIL_STIFFNESS[2]);
            add_bond_terms(bd, STENCIL[2], &fx, &fz);
        }
        add_bond(xb, za, ub, vb, STENCIL[3], STENCIL_LENGTH[3], STENCIL_STIFFNESS[3], &fx, &fz);
        add_bond(xb, za, ub, vb, STENCIL[4], STENCIL_LENGTH[4], STENCIL_STIFFNESS[4], &fx, &fz);
        if has_c {
            bc = bond_terms(ub, vb, uc, vc, STENCIL[5], STENCIL_LENGTH[5], STENCIL_STIFFNESS[5]);
            add_bond_terms(bc, STENCIL[5], &fx, &fz);
        }
        add_bond(xb, za, ub, vb, STENCIL[6], STENCIL_LENGTH[6], STENCIL_STIFFNESS[6], &fx, &fz);
        add_bond(xb, za, ub, vb, STENCIL[7], STENCIL_LENGTH[7], STENCIL_STIFFNESS[7], &fx, &fz);
        out.b = external_loads(ib, x0 + 1u, ub, vb, fx, fz, ld);
    }

    // Block c: d to its right, a below, b down to the right.
    if has_c {
        let zc = za + 1;
        fx = force_sum_zero();
        fz = force_sum_zero();
        if has_d {
            cd = bond_terms(uc, vc, ud, vd, STENCIL[0], STENCIL_LENGTH[0], STENCIL_STIFFNESS[0]);
            add_bond_terms(cd, STENCIL[0], &fx, &fz);
        }
        add_bond(xa, zc, uc, vc, STENCIL[1], STENCIL_LENGTH[1], STENCIL_STIFFNESS[1], &fx, &fz);
        add_bond(xa, zc, uc, vc, STENCIL[2], STENCIL_LENGTH[2], STENCIL_STIFFNESS[2], &fx, &fz);
        add_bond_terms(bond_terms_negated(ac), STENCIL[3], &fx, &fz);
        add_bond(xa, zc, uc, vc, STENCIL[4], STENCIL_LENGTH[4], STENCIL_STIFFNESS[4], &fx, &fz);
        add_bond(xa, zc, uc, vc, STENCIL[5], STENCIL_LENGTH[5], STENCIL_STIFFNESS[5], &fx, &fz);
        if has_b {
            add_bond_terms(bond_terms_negated(bc), STENCIL[6], &fx, &fz);
        }
        add_bond(xa, zc, uc, vc, STENCIL[7], STENCIL_LENGTH[7], STENCIL_STIFFNESS[7], &fx, &fz);
        out.c = external_loads(ic, x0, uc, vc, fx, fz, ld);
    }

    // Block d: c to its left, b below, a down to the left.
    if has_d {
        let xd = xa + 1;
        let zd = za + 1;
        fx = force_sum_zero();
        fz = force_sum_zero();
        add_bond(xd, zd, ud, vd, STENCIL[0], STENCIL_LENGTH[0], STENCIL_STIFFNESS[0], &fx, &fz);
        add_bond_terms(bond_terms_negated(cd), STENCIL[1], &fx, &fz);
        add_bond(xd, zd, ud, vd, STENCIL[2], STENCIL_LENGTH[2], STENCIL_STIFFNESS[2], &fx, &fz);
        add_bond_terms(bond_terms_negated(bd), STENCIL[3], &fx, &fz);
        add_bond(xd, zd, ud, vd, STENCIL[4], STENCIL_LENGTH[4], STENCIL_STIFFNESS[4], &fx, &fz);
        add_bond(xd, zd, ud, vd, STENCIL[5], STENCIL_LENGTH[5], STENCIL_STIFFNESS[5], &fx, &fz);
        add_bond(xd, zd, ud, vd, STENCIL[6], STENCIL_LENGTH[6], STENCIL_STIFFNESS[6], &fx, &fz);
        add_bond_terms(bond_terms_negated(ad), STENCIL[7], &fx, &fz);
        out.d = external_loads(id, x0 + 1u, ud, vd, fx, fz, ld);
    }
    return out;
}
