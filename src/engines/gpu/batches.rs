//! The engine's steps in batches: each batch is one submit of its
//! dispatches, its status copy and its output records, mapped
//! asynchronously; `advance` keeps at most `IN_FLIGHT` (or, running ahead,
//! `GpuOptions::run_ahead`) of them on the device and retires the oldest
//! first, reading each scene's blow-up and samples.

use super::batch_sizes::{IN_FLIGHT, ONE_STEP_BATCH, PERSISTENT_BATCH};
use super::buffers::{gpu_junction_springs, STATUS_BYTES};
use super::layout::{self, GpuBatch, GpuStatus};
use super::precision::{Coord, GpuReal};
use super::shaders::Kernel;
use super::{device_timer, recorder, GpuEngine};
use crate::engines::{blow_up, EngineError};
use crate::model::real::Coordinate;
use crate::model::Driver;
use std::sync::mpsc;

/// A submitted batch whose status copy is being mapped.
pub(super) struct InFlight {
    staging: wgpu::Buffer,
    submission: wgpu::SubmissionIndex,
    mapped: mpsc::Receiver<Result<(), wgpu::BufferAsyncError>>,
    first_step: u64,
    /// The persistent kernel's step counter once this batch has run.
    persistent_steps: u32,
    /// The batch's output records, mapped with its status.
    records: Option<(
        recorder::Pending,
        mpsc::Receiver<Result<(), wgpu::BufferAsyncError>>,
    )>,
    /// Its dispatches, where they are timed one by one.
    marks: Option<device_timer::BatchMarks>,
}

/// How a dispatch learns its step offset: as an immediate
/// (`KernelBuild::step_immediate`), with group 1 bound once a pass, or as a
/// dynamic offset into the step offsets' table, group 1 bound again at
/// each dispatch.
struct StepOffsets<'a> {
    immediate: bool,
    /// Group 1: the step offsets' table and the batches.
    group: &'a wgpu::BindGroup,
    /// The table's stride (bytes from one step offset to the next).
    stride: u64,
}

impl StepOffsets<'_> {
    /// Binds group 1 for the whole pass where the offsets are immediates.
    fn bind(&self, pass: &mut wgpu::ComputePass) {
        if self.immediate {
            pass.set_bind_group(1, self.group, &[0]);
        }
    }

    /// The next dispatch's step offset: `index`.
    fn set(&self, pass: &mut wgpu::ComputePass, index: u64) {
        debug_assert!(
            self.immediate || index < ONE_STEP_BATCH,
            "past the offsets' table"
        );
        match self.immediate {
            true => pass.set_immediates(0, bytemuck::bytes_of(&(index as u32))),
            false => pass.set_bind_group(1, self.group, &[(index * self.stride) as u32]),
        }
    }
}

impl<T: GpuReal> GpuEngine<T> {
    /// Submits `steps` steps from the current one (or, with `forces_only`,
    /// the forces of the current state where they are not ready), and the
    /// copy of the status.
    pub(super) fn submit_batch(
        &mut self,
        steps: u64,
        forces_only: bool,
        planned: Vec<recorder::Planned>,
    ) -> Result<(), EngineError> {
        while self.in_flight.len() >= IN_FLIGHT.max(self.lead + 1) {
            self.retire_oldest()?;
        }
        let batches: Vec<GpuBatch<T>> = self
            .scenes
            .iter()
            .map(|scene| {
                let mut batch =
                    GpuBatch::new(&scene.consts, self.step, steps as u32, scene.drive_origin);
                batch.forces_ready = scene.forces_ready as u32;
                batch.forces_only = forces_only as u32;
                batch.steps_per_dispatch = self.steps_per_dispatch as u32;
                batch.parity = self.current as u32;
                batch.records = planned.len() as u32;
                batch
            })
            .collect();
        self.buffers
            .batches
            .write(&self.ctx.queue, 0, bytemuck::cast_slice(&batches));
        // The step after each dispatch (one-step and tiled kernels), which
        // the tiled kernel reads.
        let ends = match self.kernel.is_persistent() {
            true => Vec::new(),
            false => super::tiles::dispatch_ends(self.kernel, steps, self.steps_per_dispatch),
        };
        // Which of them end a dispatch: all but where the tiled kernel
        // chains its rounds.
        let ending = super::tiles::rounds_ending_dispatches(&ends, self.chain);
        let tiled = self.tiles.as_ref();
        let dispatch_count = ending.iter().filter(|&&e| e).count() as u64;
        if self.tiles.is_some() {
            let words = super::tiles::tile_end_words(&ends, &ending);
            self.buffers.tile_scratch[4].write(&self.ctx.queue, 0, bytemuck::cast_slice(&words));
        }
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("steps"),
            });
        let scene_count = self.scenes.len() as u32;
        let timer_slot = self.timer.as_mut().map(|t| t.take_slot());
        let mut marks = timer_slot.and_then(device_timer::DeviceTimer::marks);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("steps"),
                timestamp_writes: self
                    .timer
                    .as_ref()
                    .zip(timer_slot)
                    .map(|(t, k)| t.pass_writes(k)),
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.state_group, &[]);
            let step_offsets = StepOffsets {
                immediate: self.build.step_immediate,
                group: &self.batch_group,
                stride: self.buffers.offset_stride,
            };
            step_offsets.bind(&mut pass);
            match self.kernel {
                Kernel::OneStep | Kernel::OneStepLanes | Kernel::Tiled => {
                    // A dispatch per step, or the tiled kernel's of up to
                    // its halo's steps after one gather. Both record their
                    // samples in their steps: a sample's step is the
                    // one-step kernels' recording variant, and the tiled
                    // kernel's (recording) steps find theirs.
                    if let Some(tiled) = tiled {
                        step_offsets.set(&mut pass, 0);
                        pass.set_pipeline(&tiled.gather);
                        pass.dispatch_workgroups(self.groups.0, self.groups.1, scene_count);
                        pass.set_pipeline(&self.pipeline);
                    }
                    let mut samples = planned.iter().peekable();
                    let mut first = 0;
                    // The first round of the dispatch under way.
                    let mut first_round = 0;
                    for (d, &end) in ends.iter().enumerate() {
                        if !ending[d] {
                            // A chained round: its dispatch is the one of
                            // the round that ends it.
                            if !forces_only {
                                self.current = (self.current + (end - first) as usize) % 2;
                            }
                            first = end;
                            continue;
                        }
                        // The tiled kernel's dispatch finds its rounds'
                        // steps in tile_ends from its first round's; a
                        // one-step dispatch is its step.
                        let index = if tiled.is_some() {
                            first_round as u64
                        } else {
                            first
                        };
                        first_round = d + 1;
                        step_offsets.set(&mut pass, index);
                        // A one-step kernel's sample: the step that ends
                        // this dispatch.
                        let i = end - 1;
                        let sample = match tiled {
                            Some(_) => None,
                            None => samples.next_if(|p| p.offset == i),
                        };
                        debug_assert!(
                            tiled.is_some() || samples.peek().is_none_or(|p| p.offset > i)
                        );
                        let record_step = sample.and(self.record_step.as_ref());
                        debug_assert_eq!(sample.is_some(), record_step.is_some());
                        // With the dispatch timing: a sample's step dispatch
                        // between two timestamps.
                        let mut step_marked = false;
                        if let (Some(t), Some(m), Some(_)) =
                            (self.timer.as_ref(), marks.as_mut(), sample)
                        {
                            step_marked = m.marks_before_step();
                            if step_marked {
                                t.mark(&mut pass, m);
                            }
                        }
                        if let Some(pipeline) = record_step {
                            pass.set_pipeline(pipeline);
                        }
                        pass.dispatch_workgroups(self.groups.0, self.groups.1, scene_count);
                        if record_step.is_some() {
                            pass.set_pipeline(&self.pipeline);
                        }
                        if let Some(m) = marks.as_mut() {
                            m.step_dispatched();
                        }
                        if let (Some(t), Some(m), Some(p)) =
                            (self.timer.as_ref(), marks.as_mut(), sample)
                        {
                            t.mark(&mut pass, m);
                            m.push_sample(p.offset, step_marked);
                        }
                        if !forces_only {
                            self.current = (self.current + (end - first) as usize) % 2;
                        }
                        first = end;
                    }
                    // The batch's samples: their partials added, and
                    // which were due decided (record_batch.wgsl).
                    if let Some(finish) =
                        self.record_finish.as_ref().filter(|_| !planned.is_empty())
                    {
                        if let (Some(t), Some(m)) = (self.timer.as_ref(), marks.as_mut()) {
                            t.mark(&mut pass, m);
                            m.finish_marked();
                        }
                        step_offsets.set(&mut pass, 0);
                        pass.set_pipeline(finish);
                        // A workgroup per sample and scene.
                        pass.dispatch_workgroups(planned.len() as u32, 1, scene_count);
                        self.output_dispatches += 1;
                    }
                    self.dispatches += dispatch_count;
                    if let Some(m) = marks.as_mut() {
                        m.set_steps(dispatch_count);
                    }
                }
                Kernel::Persistent | Kernel::Resident => {
                    // A workgroup a group of scenes.
                    let workgroups = scene_count.div_ceil(self.group_scenes);
                    for d in 0..steps.div_ceil(self.steps_per_dispatch) {
                        step_offsets.set(&mut pass, d);
                        pass.dispatch_workgroups(1, 1, workgroups);
                        self.dispatches += 1;
                    }
                    if let Some(m) = marks.as_mut() {
                        m.set_steps(steps.div_ceil(self.steps_per_dispatch));
                    }
                    self.persistent_steps = self.persistent_steps.wrapping_add(steps as u32);
                }
            }
        }
        let status_size = (self.scenes.len() * STATUS_BYTES) as u64;
        let staging_size = status_size
            + self
                .timer
                .as_ref()
                .map_or(0, device_timer::DeviceTimer::staging_bytes);
        let staging = self.spare_staging.pop().unwrap_or_else(|| {
            self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("status readback"),
                size: staging_size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let status = self.buffers.status.range(0, status_size);
        encoder.copy_buffer_to_buffer(status.buffer, status.offset, &staging, 0, status_size);
        // The pass's timestamps after the statuses (a multiple of 8 bytes).
        if let (Some(timer), Some(slot)) = (self.timer.as_ref(), timer_slot) {
            timer.copy_out(&mut encoder, slot, marks.as_ref(), &staging, status_size);
        }
        let pending = match self.recorder.as_mut() {
            Some(rec) => rec.copy_out(&self.ctx.device, &mut encoder, planned),
            None => None,
        };
        let submission = self.ctx.queue.submit([encoder.finish()]);
        let map = |buffer: &wgpu::Buffer| {
            let (tx, rx) = mpsc::channel();
            buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                let _ = tx.send(r);
            });
            rx
        };
        let rx = map(&staging);
        let records = pending.map(|p| {
            let rx = map(recorder::Recorder::<T>::staging(&p));
            (p, rx)
        });
        self.in_flight.push_back(InFlight {
            staging,
            submission,
            mapped: rx,
            first_step: self.step,
            persistent_steps: self.persistent_steps,
            records,
            marks,
        });
        for scene in &mut self.scenes {
            scene.forces_ready = forces_only;
        }
        if !forces_only {
            self.step += steps;
        }
        Ok(())
    }

    /// Waits for the oldest batch and records each scene's blow-up; one
    /// scene's blow-up is this engine's error (an ensemble's scenes keep
    /// theirs, `GpuEnsemble::failure`).
    pub(super) fn retire_oldest(&mut self) -> Result<(), EngineError> {
        let Some(batch) = self.in_flight.pop_front() else {
            return Ok(());
        };
        self.ctx
            .device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(batch.submission),
                timeout: None,
            })
            // A submit the device refused (its validation error) shows as
            // a wait on a submission that never was: report the refusal.
            .map_err(|e| match self.ctx.check() {
                Err(refused) => refused,
                Ok(()) => EngineError::Gpu(format!("device lost: {e}")),
            })?;
        batch
            .mapped
            .recv()
            .map_err(|e| EngineError::Gpu(format!("status readback: {e}")))?
            .map_err(|e| EngineError::Gpu(format!("status readback: {e}")))?;
        let statuses: Vec<GpuStatus> = {
            let view = batch
                .staging
                .slice(..)
                .get_mapped_range()
                .map_err(|e| EngineError::Gpu(format!("status readback: {e}")))?;
            let status_size = self.scenes.len() * STATUS_BYTES;
            if let Some(timer) = self.timer.as_mut() {
                timer.add(&view[status_size..], batch.marks.as_ref());
            }
            bytemuck::cast_slice(&view[..status_size]).to_vec()
        };
        batch.staging.unmap();
        self.spare_staging.push(batch.staging);
        self.ctx.check()?;
        if let Some((pending, mapped)) = batch.records {
            mapped
                .recv()
                .map_err(|e| EngineError::Gpu(format!("record readback: {e}")))?
                .map_err(|e| EngineError::Gpu(format!("record readback: {e}")))?;
            // After a blow-up only the samples before it are kept (a
            // scene stopped earlier keeps none: its state stands still).
            let before: Vec<u64> = self
                .scenes
                .iter()
                .zip(&statuses)
                .map(|(scene, s)| match scene.failure {
                    Some(_) => 0,
                    None if s.flag != 0 => batch.first_step + s.step as u64 + 1,
                    None => u64::MAX,
                })
                .collect();
            let rec = self.recorder.as_mut().expect("records need a recorder");
            let samples = rec.decode(pending, &before).map_err(EngineError::Gpu)?;
            for (mine, new) in self.samples.iter_mut().zip(samples) {
                mine.extend(new);
            }
        }
        for status in &statuses {
            self.lane_levels = self.lane_levels.max(status.lane_levels);
        }
        if let Some(status) = statuses.iter().find(|s| s.stalled_tile != 0) {
            // The adapter, not a scene: every scene's run is in doubt.
            self.in_flight.clear();
            return Err(EngineError::Gpu(format!(
                "{} did not run a scene's chained tiles at once: tile {} waited for its \
                 neighbours past {} polls; run the tiled kernel unchained (without \
                 --gpu-chained-tiles) or another --gpu-path",
                self.ctx.info.name,
                status.stalled_tile - 1,
                self.chain.map_or(0, |c| c.polls)
            )));
        }
        if statuses.iter().any(|s| s.straddled_subgroup != 0) {
            // Threads of one scene stepped another's: every scene's run is
            // in doubt.
            self.in_flight.clear();
            return Err(EngineError::Gpu(format!(
                "{}'s subgroups held threads of two scenes of a persistent workgroup ({} scenes \
                 of {} threads): use --gpu-group-scenes 1, or more --gpu-threads",
                self.ctx.info.name,
                self.group_scenes,
                self.scene_threads()
            )));
        }
        for (scene, status) in self.scenes.iter_mut().zip(&statuses) {
            if scene.failure.is_some() {
                continue;
            }
            if self.kernel.is_persistent()
                && status.flag == 0
                && status.persistent_steps != batch.persistent_steps
            {
                return Err(EngineError::Gpu(format!(
                    "{} cut a persistent dispatch short ({} steps run in all, {} asked for): \
                     use --gpu-path one-step",
                    self.ctx.info.name, status.persistent_steps, batch.persistent_steps
                )));
            }
            if status.flag != 0 {
                // The update of step first + s led to step first + s + 1.
                let step = batch.first_step + status.step as u64 + 1;
                let u = [status.ux as f64, status.uz as f64];
                let v = [status.vx as f64, status.vz as f64];
                scene.failure = Some(blow_up(&scene.model, step, status.block as usize, u, v));
            }
        }
        if !self.ensemble {
            if let Some(e) = self.scenes[0].failure.take() {
                self.in_flight.clear();
                if let EngineError::BlowUp { step, .. } = e {
                    self.step = step;
                }
                return Err(e);
            }
        }
        Ok(())
    }

    /// Waits for every submitted batch.
    pub(super) fn drain(&mut self) -> Result<(), EngineError> {
        self.retire_to(0)
    }

    /// Waits for the oldest batches until at most `left` are running.
    pub(super) fn retire_to(&mut self, left: usize) -> Result<(), EngineError> {
        while self.in_flight.len() > left {
            self.retire_oldest()?;
        }
        Ok(())
    }

    /// Once, when driving starts (before the forces of that step): fixes
    /// each scene's driver origin and applies its trigger's initial
    /// junction forces (host code shared with the CPU).
    pub(super) fn begin_driving(&mut self) -> Result<(), EngineError> {
        for k in 0..self.scenes.len() {
            let snap = self.read_state(k)?;
            let scene = &mut self.scenes[k];
            if let Driver::SideSpring { row, .. } = scene.model.driver {
                scene.drive_origin = Coord::<T>::from_f64(snap.disp[row * scene.model.nx][0]);
            }
            if scene.model.sets_anchors_at_drive_start() {
                let anchors = crate::engines::trigger::trigger_anchors(&scene.model, &snap);
                let spring = gpu_junction_springs::<T>(&anchors, &snap.junction_stiffness);
                let at = (k * self.shape.junctions * Self::SPRING_BYTES) as u64;
                self.buffers.junction_spring.write(
                    &self.ctx.queue,
                    at,
                    bytemuck::cast_slice(&spring),
                );
                self.forget_junction_sums(k);
            }
            // The forces of this step change with the driver: recompute them.
            self.scenes[k].forces_ready = false;
        }
        Ok(())
    }

    /// The most steps one batch (one submit) holds with this kernel: an
    /// advance of more is cut into batches, which the device runs while
    /// the host encodes the next.
    pub(super) fn batch_steps(&self) -> u64 {
        match self.kernel {
            Kernel::OneStep | Kernel::OneStepLanes | Kernel::Tiled => ONE_STEP_BATCH,
            Kernel::Persistent | Kernel::Resident => {
                PERSISTENT_BATCH.min(self.steps_per_dispatch * ONE_STEP_BATCH)
            }
        }
    }

    /// Advances every scene `n` steps, in batches that never cross the end
    /// of the ramp or of the normal-load phase.
    pub(super) fn advance_steps(&mut self, n: u64) -> Result<(), EngineError> {
        let (prep, ramp) = (
            self.scenes[0].model.prep_steps,
            self.scenes[0].model.ramp_steps,
        );
        let max_batch = self.batch_steps();
        let mut left = n;
        while left > 0 {
            // A batch's loads are of one kind throughout, and while driving
            // it does not cross an anchor of the drive (layout::drive_anchor).
            let mut k = left.min(max_batch);
            if self.step >= prep {
                let consts = &self.scenes[0].consts;
                let next = layout::drive_anchor(consts, self.step) + layout::DRIVE_ANCHOR_STEPS;
                k = k.min(next - self.step);
            }
            for boundary in [ramp, prep] {
                if self.step < boundary {
                    k = k.min(boundary - self.step);
                }
            }
            let planned = match self.recorder.as_mut() {
                Some(rec) => {
                    let (planned, fits) = rec.plan_batch(self.step, k);
                    k = fits;
                    rec.write_entries(&self.ctx.queue, &planned);
                    planned
                }
                None => Vec::new(),
            };
            self.submit_batch(k, false, planned)?;
            left -= k;
            if self.step == prep {
                self.begin_driving()?;
            }
        }
        // The sample of the step reached, if it is one: after the forces
        // of that step (which the next step then reads).
        if let Some(rec) = self.recorder.as_mut() {
            let planned = rec.plan_now(self.step);
            if !planned.is_empty() {
                rec.write_entries(&self.ctx.queue, &planned);
                self.submit_batch(1, true, planned)?;
            }
        }
        // The run's last step is waited for: its caller then finishes.
        if self.step >= self.scenes[0].model.total_steps() {
            self.drain()
        } else {
            self.retire_to(self.lead)
        }
    }

    /// Computes the forces of the current state of the scenes whose forces
    /// are not ready (a snapshot describes one instant).
    pub(super) fn ready_forces(&mut self) -> Result<(), EngineError> {
        self.drain()?;
        if self.scenes.iter().any(|s| !s.forces_ready) {
            self.submit_batch(1, true, Vec::new())?;
            self.drain()?;
        }
        Ok(())
    }
}
