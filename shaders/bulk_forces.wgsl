// Springs, dashpots, foundation and external loads on one block.
// CPU twin: src/engines/kernels/bulk_forces.rs bulk_force. Terms a scene does not use
// are removed by the pipeline-overridable constants below.
// import: common, coordinates, scene, state

override DAMPING_FORM: u32 = 1u;      // 0 none, 1 full relative velocity, 2 bond-projected
override USE_FOUNDATION: bool = true;
override USE_TOP_LOADS: bool = true;
override USE_SIDE_SPRING: bool = true;
override USE_RELAXATION: bool = true;    // any absolute damping (relaxation or driving)
override USE_PRESTRESS: bool = true;

fn top_share(ix: u32) -> real {
    if c.nx == 1u {
        return 1.0;
    }
    if ix == 0u || ix == c.nx - 1u {
        return c.top_share_edge;
    }
    return c.top_share_full;
}

// Relative line load of column ix (CPU twin: laws::normal_profile).
fn normal_profile(ix: u32) -> real {
    if c.nx == 1u {
        return 1.0;
    }
    let x = real(ix) / real(c.nx - 1u);
    return 1.0 + c.normal_slope * (1.0 - (x + x));
}

// What one bond adds to a block's force sums: q·r0 (mixed f32's split
// bonds only), then the spring and dashpot terms along x and along z.
// Every term is an odd function of the bond's offset, displacement and
// velocity differences, and round-to-nearest is symmetric, so the bond
// seen from its other end adds exactly these terms negated
// (bond_terms_negated): bulk_patch.wgsl computes a bond inside its patch
// once.
struct BondTerms {
    axial: vec2<real>,
    along_x: vec2<real>,
    along_z: vec2<real>,
}

// The terms of the bond from a block (displacement ui, velocity vi) to its
// neighbour at offset d (uj, vj), rest length `length` and stiffness
// `stiffness` in lattice units. Called once per stencil entry with
// constant arguments: a loop over the stencil indexed its constant tables
// at run time, which drivers may keep in per-thread memory.
fn bond_terms(ui: Disp, vi: vec2<real>, uj: Disp, vj: vec2<real>, d: vec2<i32>, length: real, stiffness: real) -> BondTerms {
    let r0 = vec2<real>(real(d.x) * c.spacing, real(d.y) * c.spacing);
    let rest = length * c.spacing;
    let kb = stiffness * c.k;
    let du = vec2<real>(coord_diff(uj.x, ui.x), coord_diff(uj.z, ui.z));
    let r = r0 + du;
    let len = sqrt(r.x * r.x + r.y * r.y);
    // Elongation without cancellation: stretch = (|r|² − l²)/(|r| + l) =
    // num/over. Each force below divides once by a denominator that folds
    // this division in (one division a bond, not two).
    let num = 2.0 * (r0.x * du.x + r0.y * du.y) + (du.x * du.x + du.y * du.y);
    let over = len + rest;
    var damper = vec2<real>(0.0, 0.0);
    let dv = vj - vi;
    if SPLITS_BONDS {
        // Mixed f32: r0 + du would round du to ulp(r0), about two steps
        // of creep, and turn the bond's direction in stairs; the force
        // q·r is summed as q·r0 + q·du instead (CPU twin: bulk_force).
        // q = k·stretch/|r| with |r| = rest + stretch = (rest·over + num)/over.
        let len_times_over = rest * over + num;
        let q = kb * num / len_times_over;
        if DAMPING_FORM == 2u {
            let inv = over / len_times_over;
            let n0 = vec2<real>(r0.x * inv, r0.y * inv);
            let n1 = vec2<real>(du.x * inv, du.y * inv);
            let along = c.eta * ((dv.x * n0.x + dv.y * n0.y) + (dv.x * n1.x + dv.y * n1.y));
            damper = vec2<real>(along * n0.x + along * n1.x, along * n0.y + along * n1.y);
        } else if DAMPING_FORM != 0u {
            damper = vec2<real>(c.eta * dv.x, c.eta * dv.y);
        }
        return BondTerms(
            vec2<real>(q * r0.x, q * r0.y),
            vec2<real>(q * du.x, damper.x),
            vec2<real>(q * du.y, damper.y),
        );
    }
    // The spring force k·stretch·r/|r| = (k·num/(over·|r|))·r.
    let spring_per_length = kb * num / (over * len);
    if DAMPING_FORM == 2u {
        let inv_len = 1.0 / len;
        let n = vec2<real>(r.x * inv_len, r.y * inv_len);
        let along = c.eta * (dv.x * n.x + dv.y * n.y);
        damper = vec2<real>(along * n.x, along * n.y);
    } else if DAMPING_FORM != 0u {
        damper = vec2<real>(c.eta * dv.x, c.eta * dv.y);
    }
    return BondTerms(vec2<real>(0.0, 0.0), vec2<real>(spring_per_length * r.x, damper.x), vec2<real>(spring_per_length * r.y, damper.y));
}

// The same bond seen from the neighbour's end (offset −d): every term
// negated, exactly.
fn bond_terms_negated(t: BondTerms) -> BondTerms {
    return BondTerms(-t.axial, -t.along_x, -t.along_z);
}

// A bond's terms at offset d (a constant of each call) added to a block's
// sums, in the order the CPU twin adds them.
fn add_bond_terms(t: BondTerms, d: vec2<i32>, fx: ptr<function, force_sum>, fz: ptr<function, force_sum>) {
    var sx = *fx;
    var sz = *fz;
    if SPLITS_BONDS {
        // A stencil entry along an axis has r0 = 0 across it: its q·r0 term
        // is ±0, and adding ±0 leaves a compensated sum's bits as they are
        // (neither of its words is −0), so the term is not added.
        if d.x != 0 {
            sx = force_sum_add(sx, t.axial.x);
        }
        if d.y != 0 {
            sz = force_sum_add(sz, t.axial.y);
        }
    }
    *fx = force_sum_add_bond(sx, t.along_x.x, t.along_x.y);
    *fz = force_sum_add_bond(sz, t.along_z.x, t.along_z.y);
}

// Whether add_bond loads every neighbour and selects the missing ones'
// terms away (the one-step kernels: the host sets it), rather than
// branching around a missing neighbour's loads. With neither that branch
// nor one between two state copies (state_one_step.wgsl), a block's eight
// neighbours' loads can be in flight together, where each had waited for
// the bond before it; a kernel holding its state in workgroup memory, or
// one for which more registers cost a workgroup an SM (the persistent
// kernel), keeps the branch.
override NEIGHBOURS_WITHOUT_BRANCHES: bool = false;

// Bond of the block at column ix and row iz (displacement ui, velocity vi)
// to its neighbour at offset d, if that is in the lattice, added to the
// block's sums.
fn add_bond(
    ix: i32,
    iz: i32,
    ui: Disp,
    vi: vec2<real>,
    d: vec2<i32>,
    length: real,
    stiffness: real,
    fx: ptr<function, force_sum>,
    fz: ptr<function, force_sum>,
) {
    let jx = ix + d.x;
    let jz = iz + d.y;
    let exists = jx >= 0 && jz >= 0 && jx < i32(c.nx) && jz < i32(c.nz);
    if NEIGHBOURS_WITHOUT_BRANCHES {
        // A missing neighbour's slot is the nearest one in the lattice.
        let cx = u32(clamp(jx, 0, i32(c.nx) - 1));
        let cz = u32(clamp(jz, 0, i32(c.nz) - 1));
        let j = cz * c.nx + cx;
        let t = bond_terms(ui, vi, load_disp_at(j, cx, cz), load_vel_at(j, cx, cz), d, length, stiffness);
        // The sums with the bond added, kept where the neighbour exists:
        // the same arithmetic as the branch's (selecting the terms instead
        // would change where a compiler may fuse their products into the
        // sums, and so their rounding).
        var sx = *fx;
        var sz = *fz;
        add_bond_terms(t, d, &sx, &sz);
        *fx = select(*fx, sx, exists);
        *fz = select(*fz, sz, exists);
        return;
    }
    if !exists {
        return;
    }
    add_neighbour_bond(u32(jz) * c.nx + u32(jx), u32(jx), u32(jz), ui, vi, d, length, stiffness, fx, fz);
}

// The bond to neighbour j (column jx, row jz, at offset d), which exists,
// added to the block's sums.
fn add_neighbour_bond(j: u32, jx: u32, jz: u32, ui: Disp, vi: vec2<real>, d: vec2<i32>, length: real, stiffness: real, fx: ptr<function, force_sum>, fz: ptr<function, force_sum>) {
    let uj = load_disp_at(j, jx, jz);
    let vj = load_vel_at(j, jx, jz);
    add_bond_terms(bond_terms(ui, vi, uj, vj, d, length, stiffness), d, fx, fz);
}

// add_bond of a block inside the lattice's rim (block i at column ix, row
// iz; block_span): every neighbour exists, so no bound is checked. The
// checks were a fifth of a bond's instructions (RADV, Table S1), and nine
// blocks in ten of Table S1 are inside.
fn add_inner_bond(i: u32, ix: u32, iz: u32, ui: Disp, vi: vec2<real>, d: vec2<i32>, length: real, stiffness: real, fx: ptr<function, force_sum>, fz: ptr<function, force_sum>) {
    let j = u32(i32(i) + d.y * i32(c.nx) + d.x);
    add_neighbour_bond(j, u32(i32(ix) + d.x), u32(i32(iz) + d.y), ui, vi, d, length, stiffness, fx, fz);
}

// bulk_force of a block inside the lattice's rim (column and row in
// 1 ..= n − 2): the same bits, without the bounds.
fn inner_bulk_force(i: u32, column: u32, row: u32, ld: Loads) -> vec2<real> {
    let ui = load_disp_at(i, column, row);
    let vi = load_vel_at(i, column, row);
    var fx = force_sum_zero();
    var fz = force_sum_zero();
    add_inner_bond(i, column, row, ui, vi, STENCIL[0], STENCIL_LENGTH[0], STENCIL_STIFFNESS[0], &fx, &fz);
    add_inner_bond(i, column, row, ui, vi, STENCIL[1], STENCIL_LENGTH[1], STENCIL_STIFFNESS[1], &fx, &fz);
    add_inner_bond(i, column, row, ui, vi, STENCIL[2], STENCIL_LENGTH[2], STENCIL_STIFFNESS[2], &fx, &fz);
    add_inner_bond(i, column, row, ui, vi, STENCIL[3], STENCIL_LENGTH[3], STENCIL_STIFFNESS[3], &fx, &fz);
    add_inner_bond(i, column, row, ui, vi, STENCIL[4], STENCIL_LENGTH[4], STENCIL_STIFFNESS[4], &fx, &fz);
    add_inner_bond(i, column, row, ui, vi, STENCIL[5], STENCIL_LENGTH[5], STENCIL_STIFFNESS[5], &fx, &fz);
    add_inner_bond(i, column, row, ui, vi, STENCIL[6], STENCIL_LENGTH[6], STENCIL_STIFFNESS[6], &fx, &fz);
    add_inner_bond(i, column, row, ui, vi, STENCIL[7], STENCIL_LENGTH[7], STENCIL_STIFFNESS[7], &fx, &fz);
    return external_loads(i, column, ui, vi, fx, fz, ld);
}

// Block i at column column and row row (i = row·nx + column: the caller
// has them, or divides once).
fn bulk_force(i: u32, column: u32, row: u32, ld: Loads) -> vec2<real> {
    let ix = i32(column);
    let iz = i32(row);
    let ui = load_disp_at(i, column, row);
    let vi = load_vel_at(i, column, row);
    // Compensated sums in mixed precision (force_sum_add says why), the
    // bonds in stencil order.
    var fx = force_sum_zero();
    var fz = force_sum_zero();
    add_bond(ix, iz, ui, vi, STENCIL[0], STENCIL_LENGTH[0], STENCIL_STIFFNESS[0], &fx, &fz);
    add_bond(ix, iz, ui, vi, STENCIL[1], STENCIL_LENGTH[1], STENCIL_STIFFNESS[1], &fx, &fz);
    add_bond(ix, iz, ui, vi, STENCIL[2], STENCIL_LENGTH[2], STENCIL_STIFFNESS[2], &fx, &fz);
    add_bond(ix, iz, ui, vi, STENCIL[3], STENCIL_LENGTH[3], STENCIL_STIFFNESS[3], &fx, &fz);
    add_bond(ix, iz, ui, vi, STENCIL[4], STENCIL_LENGTH[4], STENCIL_STIFFNESS[4], &fx, &fz);
    add_bond(ix, iz, ui, vi, STENCIL[5], STENCIL_LENGTH[5], STENCIL_STIFFNESS[5], &fx, &fz);
    add_bond(ix, iz, ui, vi, STENCIL[6], STENCIL_LENGTH[6], STENCIL_STIFFNESS[6], &fx, &fz);
    add_bond(ix, iz, ui, vi, STENCIL[7], STENCIL_LENGTH[7], STENCIL_STIFFNESS[7], &fx, &fz);
    return external_loads(i, column, ui, vi, fx, fz, ld);
}

// The loads that do not come from bonds, added to block i's bond sums in
// the CPU twin's order (external_loads): foundation and interface
// prestress, top loads, side spring, absolute damping; the total rounded
// once.
fn external_loads(i: u32, column: u32, ui: Disp, vi: vec2<real>, bond_x: force_sum, bond_z: force_sum, ld: Loads) -> vec2<real> {
    var fx = bond_x;
    var fz = bond_z;
    let fl = flags[i];
    if USE_FOUNDATION && (fl & FLAG_INTERFACE) != 0u {
        fz = force_sum_add(fz, foundation_normal(coord_value(ui.z)));
    }
    if USE_PRESTRESS && (fl & FLAG_INTERFACE) != 0u {
        let total = select(ld.interface_shear_total, ld.strip_shear_total, column < c.strip_blocks);
        fx = force_sum_add(fx, total * (top_share(column) * normal_profile(column)));
    }
    if USE_TOP_LOADS && (fl & FLAG_TOP) != 0u {
        let share = top_share(column);
        fz = force_sum_add(fz, -(ld.normal_total * (share * normal_profile(column))));
        fx = force_sum_add(fx, ld.top_tangential_total * share);
    }
    if USE_SIDE_SPRING && (fl & FLAG_DRIVEN) != 0u && !ld.preparing {
        fx = force_sum_add(fx, c.drive_stiffness * coord_diff(ld.drive_target, ui.x));
    }
    if USE_RELAXATION {
        fx = force_sum_add(fx, -(ld.absolute_eta * vi.x));
        fz = force_sum_add(fz, -(ld.absolute_eta * vi.y));
    }
    return vec2<real>(force_sum_value(fx), force_sum_value(fz));
}
