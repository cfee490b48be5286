// One step of the one-step kernels by 2×2 patches of blocks
// (BOND_PATCHES, GpuOptions::bond_patches): a thread per patch of the rows
// above the interface computes the patch's bulk forces, each bond inside
// it once (bulk_patch.wgsl), then the patch's four leapfrog updates; the
// interface row keeps a thread per block, whose junction walk a patch would
// double. A quarter of the threads for the bulk: the large lattices'
// variant, where threads are plenty. A sample's partials follow the
// threads (patch_items.wgsl): the recording variant (STEP_RECORDS) sums
// each workgroup's items.
// CPU twin: src/engines/kernels/bulk_forces.rs bulk_force_patch (the
// forces), src/engines/kernels/verlet.rs verlet (the update).
// import: bulk_patch, common, patch_items, record_common, record_step, scene, state, step_forces, verlet

override BOND_PATCHES: bool = false;

// Thread t of the one-step kernels' patched variant, item t of
// patch_items.wgsl: interface block t as in one_step (its junction walk
// stays one block long; one_step_lanes' junction workgroups step the
// interface row, and its other threads start past it), or a patch.
// Returns the item's part of the step's sample, its blocks in patch order
// (where `computed`: the recording variant's sample that may be due;
// no_sums otherwise).
fn step_by_patches(t: u32, computed: bool) -> SampleSums {
    var part = no_sums();
    if scene_stopped() {
        return part;
    }
    let ld = loads_at(step_offset);
    let ready = batch.forces_ready != 0u && step_offset == 0u;
    let update = batch.forces_only == 0u;
    if t < c.nx {
        let ff = block_forces(t, ld, ready);
        if computed {
            part = step_block_sample(t, step_sample(), ff.xy, ff.z);
        }
        if update {
            verlet(t, t, 0u, ff.xy, ff.z, ld, step_offset);
        }
        return part;
    }
    let origin = patch_item_origin(t, c.nx);
    let x0 = origin.x;
    let z0 = origin.y;
    if z0 >= c.nz {
        return part;
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
    if computed {
        let e = step_sample();
        part = step_block_sample(i, e, f.a, 0.0);
        if has_b {
            part = combine(part, step_block_sample(i + 1u, e, f.b, 0.0));
        }
        if has_c {
            part = combine(part, step_block_sample(i + c.nx, e, f.c, 0.0));
            if has_b {
                part = combine(part, step_block_sample(i + c.nx + 1u, e, f.d, 0.0));
            }
        }
    }
    if !update {
        return part;
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
    return part;
}
