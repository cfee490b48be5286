// One step of the one-step kernels by 2×2 patches of blocks
// (BOND_PATCHES, GpuOptions::bond_patches): a thread per patch of the rows
// above the interface computes the patch's bulk forces, each bond inside
// it once (bulk_patch.wgsl), then the patch's four leapfrog updates; the
// interface row keeps a thread per block, whose junction walk a patch would
// double. A quarter of the threads for the bulk: the large lattices'
// variant, where threads are plenty. A sample's partials follow the
// threads (patch_items.wgsl): the recording variant (RECORD_KINETIC) sums
// the kinetic energy of a workgroup's items, and the output kernels the
// same items' sums.
// CPU twin: src/engines/kernels/bulk_forces.rs bulk_force_patch (the
// forces), src/engines/kernels/verlet.rs verlet (the update).
// import: bulk_patch, common, patch_items, record_kinetic, scene, state, step_forces, verlet

override BOND_PATCHES: bool = false;

// Thread t of the one-step kernels' patched variant, item t of
// patch_items.wgsl: interface block t as in one_step (its junction walk
// stays one block long; one_step_lanes' junction workgroups step the
// interface row, and its other threads start past it), or a patch.
// Returns the item's kinetic energy at the step's instant, its blocks in
// patch order (RECORD_KINETIC; zero otherwise).
fn step_by_patches(t: u32) -> real {
    var kinetic = real(0.0);
    if scene_stopped() {
        return kinetic;
    }
    let ld = loads_at(step_offset);
    let ready = batch.forces_ready != 0u && step_offset == 0u;
    let update = batch.forces_only == 0u;
    if t < c.nx {
        let ff = block_forces(t, ld, ready);
        if RECORD_KINETIC {
            kinetic = bulk_kinetic(t, load_vel(t), ff.xy);
        }
        if update {
            verlet(t, t, 0u, ff.xy, ff.z, ld, step_offset);
        }
        return kinetic;
    }
    let origin = patch_item_origin(t, c.nx);
    let x0 = origin.x;
    let z0 = origin.y;
    if z0 >= c.nz {
        return kinetic;
    }
    let has_b = x0 + 1u < c.nx;
    let has_c = z0 + 1u < c.nz;
    let i = z0 * c.nx + x0;
    var f: PatchForces;
    if ready {
        // A snapshot's force pass computed them.
        f.a = force[block_base() + i];
        if has_b {
            f.b = force[block_base() + i + 1u];
        }
        if has_c {
            f.c = force[block_base() + i + c.nx];
            if has_b {
                f.d = force[block_base() + i + c.nx + 1u];
            }
        }
    } else {
        f = bulk_force_patch(x0, z0, c.nx, ld);
        force[block_base() + i] = f.a;
        if has_b {
            force[block_base() + i + 1u] = f.b;
        }
        if has_c {
            force[block_base() + i + c.nx] = f.c;
            if has_b {
                force[block_base() + i + c.nx + 1u] = f.d;
            }
        }
    }
    if RECORD_KINETIC {
        kinetic = bulk_kinetic(i, load_vel(i), f.a);
        if has_b {
            kinetic += bulk_kinetic(i + 1u, load_vel(i + 1u), f.b);
        }
        if has_c {
            kinetic += bulk_kinetic(i + c.nx, load_vel(i + c.nx), f.c);
            if has_b {
                kinetic += bulk_kinetic(i + c.nx + 1u, load_vel(i + c.nx + 1u), f.d);
            }
        }
    }
    if !update {
        return kinetic;
    }
    // Blocks above the interface have no friction.
    verlet(i, x0, z0, f.a, 0.0, ld, step_offset);
    if has_b {
        verlet(i + 1u, x0 + 1u, z0, f.b, 0.0, ld, step_offset);
    }
    if has_c {
        verlet(i + c.nx, x0, z0 + 1u, f.c, 0.0, ld, step_offset);
        if has_b {
            verlet(i + c.nx + 1u, x0 + 1u, z0 + 1u, f.d, 0.0, ld, step_offset);
        }
    }
    return kinetic;
}
