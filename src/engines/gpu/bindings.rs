//! The kernels' buffer bindings, declared once: in the WGSL files
//! (`@group(g) @binding(b) var<...> name`). The host reflects them from
//! the composed module with naga, so its bind group layouts and bind
//! groups come from the shaders' own declarations and name the buffers by
//! variable name: no binding number is written on the Rust side.

/// One buffer binding a module declares.
#[derive(Debug, Clone, PartialEq)]
struct Declared {
    name: String,
    group: u32,
    binding: u32,
    ty: wgpu::BufferBindingType,
}

/// The buffer bindings of one WGSL module.
#[derive(Debug, Clone, PartialEq)]
pub struct Bindings {
    declared: Vec<Declared>,
}

impl Bindings {
    /// The bindings `src` declares (uniform and storage buffers) that its
    /// entry points use: a module also holds snippets' declarations that
    /// none of its entry points reads (the output module's `batch`), and
    /// a layout names only what the pipelines use.
    pub fn reflect(src: &str) -> Result<Bindings, String> {
        let module = naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string(src))?;
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .map_err(|e| e.emit_to_string(src))?;
        let used = |handle: naga::Handle<naga::GlobalVariable>| {
            (0..module.entry_points.len()).any(|i| !info.get_entry_point(i)[handle].is_empty())
        };
        let mut declared = Vec::new();
        for (handle, var) in module.global_variables.iter() {
            let Some(at) = &var.binding else { continue };
            if !used(handle) {
                continue;
            }
            let ty = match var.space {
                naga::AddressSpace::Uniform => wgpu::BufferBindingType::Uniform,
                naga::AddressSpace::Storage { access } => wgpu::BufferBindingType::Storage {
                    read_only: !access.contains(naga::StorageAccess::STORE),
                },
                other => {
                    return Err(format!(
                        "{:?}: unsupported binding space {other:?}",
                        var.name
                    ))
                }
            };
            declared.push(Declared {
                name: var.name.clone().unwrap_or_default(),
                group: at.group,
                binding: at.binding,
                ty,
            });
        }
        declared.sort_by_key(|d| (d.group, d.binding));
        Ok(Bindings { declared })
    }

    /// The layout entries of `group`; the bindings named in `dynamic` take
    /// a dynamic offset.
    pub fn layout(&self, group: u32, dynamic: &[&str]) -> Vec<wgpu::BindGroupLayoutEntry> {
        self.in_group(group)
            .map(|d| entry(d.binding, d.ty, dynamic.contains(&d.name.as_str())))
            .collect()
    }

    /// The entries of a bind group of `group`: each declared binding gets
    /// the resource of its name in `resources` (names the module does not
    /// declare are skipped, so one list serves every kernel).
    ///
    /// Panics when a declared binding has no resource: a programming error
    /// that the GPU tests meet at once.
    pub fn entries<'a>(
        &self,
        group: u32,
        resources: &[(&str, wgpu::BindingResource<'a>)],
    ) -> Vec<wgpu::BindGroupEntry<'a>> {
        self.in_group(group)
            .map(|d| {
                let resource = resources
                    .iter()
                    .find(|(name, _)| *name == d.name)
                    .unwrap_or_else(|| panic!("binding {} has no buffer", d.name))
                    .1
                    .clone();
                wgpu::BindGroupEntry {
                    binding: d.binding,
                    resource,
                }
            })
            .collect()
    }

    /// The bindings of either (kernels that share a layout).
    pub fn union(mut self, other: Bindings) -> Bindings {
        for d in other.declared {
            if !self.declared.contains(&d) {
                self.declared.push(d);
            }
        }
        self.declared.sort_by_key(|d| (d.group, d.binding));
        self
    }

    /// Storage buffer bindings, every group: what a pipeline layout of
    /// these bindings asks of `max_storage_buffers_per_shader_stage`.
    pub fn storage_count(&self) -> u32 {
        self.declared
            .iter()
            .filter(|d| matches!(d.ty, wgpu::BufferBindingType::Storage { .. }))
            .count() as u32
    }

    /// The binding number of variable `name` (for tests and messages).
    pub fn binding(&self, name: &str) -> Option<(u32, u32)> {
        self.declared
            .iter()
            .find(|d| d.name == name)
            .map(|d| (d.group, d.binding))
    }

    fn in_group(&self, group: u32) -> impl Iterator<Item = &Declared> {
        self.declared.iter().filter(move |d| d.group == group)
    }
}

/// A compute-stage buffer binding of a bind group layout.
pub fn entry(
    binding: u32,
    ty: wgpu::BufferBindingType,
    dynamic: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: dynamic,
            min_binding_size: None,
        },
        count: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::gpu::shaders::Kernel;

    /// The reflected layouts are the ones the host used to write by hand,
    /// and their access follows each declaration (read-only flags and
    /// constants, read-write state).
    #[test]
    fn reflected_bindings_follow_the_declarations() {
        let one_step = Bindings::reflect(&Kernel::OneStep.source::<f32>()).unwrap();
        let numbers: Vec<u32> = one_step.layout(0, &[]).iter().map(|e| e.binding).collect();
        // The state's two copies are one array each (state_one_step.wgsl).
        assert_eq!(
            numbers,
            [0, 1, 2, 5, 6, 7, 8, 9, 10, 11, 13, 14, 15, 17, 23, 25, 26]
        );
        assert_eq!(one_step.binding("disp_copies"), Some((0, 1)));
        assert_eq!(one_step.binding("vel_copies"), Some((0, 2)));
        let persistent = Bindings::reflect(&Kernel::Persistent.source::<f32>()).unwrap();
        let numbers: Vec<u32> = persistent
            .layout(0, &[])
            .iter()
            .map(|e| e.binding)
            .collect();
        assert_eq!(
            numbers,
            [0, 1, 2, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 23]
        );
        assert_eq!(persistent.binding("lane_partial"), Some((0, 12)));
        // The resident kernel shares the persistent kernel's layout.
        let resident = Bindings::reflect(&Kernel::Resident.source::<f32>()).unwrap();
        assert_eq!(resident.layout(0, &[]), persistent.layout(0, &[]));
        // A group-0 binding's access, by binding number.
        let access = |b: &Bindings, binding: u32| {
            let entry = b.layout(0, &[]).into_iter().find(|e| e.binding == binding);
            match entry.map(|e| e.ty) {
                Some(wgpu::BindingType::Buffer { ty, .. }) => ty,
                other => panic!("binding {binding}: {other:?}"),
            }
        };
        let read = wgpu::BufferBindingType::Storage { read_only: true };
        let write = wgpu::BufferBindingType::Storage { read_only: false };
        // The constants: one record per scene (a solo run is an ensemble of
        // one), read only; the flags read only, the forces written. The
        // recording variant's entries and step samples (record_step.wgsl)
        // are only read; the plans and sums it writes.
        for (module, binding, want) in [
            (&one_step, 0, read),
            (&persistent, 0, read),
            (&one_step, 6, read),
            (&one_step, 5, write),
            (&one_step, 25, read),
            (&one_step, 26, read),
            (&one_step, 13, write),
            (&one_step, 14, write),
        ] {
            assert_eq!(access(module, binding), want, "binding {binding}");
        }
        let batch = one_step.layout(1, &["step_offset"]);
        assert!(matches!(
            batch[0].ty,
            wgpu::BindingType::Buffer {
                has_dynamic_offset: true,
                ..
            }
        ));
        assert_eq!(one_step.binding("step_samples"), Some((0, 26)));
    }
}
