fn main() {
    for a in slipfront::gpu::context::adapters() {
        let l = a.limits();
        println!(
            "{:?}: storage/stage {} storage align {} uniform align {}",
            a.get_info().name,
            l.max_storage_buffers_per_shader_stage,
            l.min_storage_buffer_offset_alignment,
            l.min_uniform_buffer_offset_alignment
        );
    }
}
