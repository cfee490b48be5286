//! Prints the `/global` series of a run file as CSV (time, step, drive
//! ratio, kinetic energy, ruptures, pinned fraction), or with `--jumps` the
//! `/fast_forward` records, for quick looks.
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .expect("usage: dump_global [--jumps] RUN.mcap");
    let run = slipfront::io::output::reader::RunFile::read(std::path::Path::new(path))
        .unwrap_or_else(|e| panic!("{e}"));
    if args.iter().any(|a| a == "--jumps") {
        println!("start_time,end_time,predicted_change,block,junction,dropped_energy");
        for j in &run.fast_forward {
            println!(
                "{:.9e},{:.9e},{:.9e},{},{},{:.3e}",
                j.start_time, j.end_time, j.predicted_change, j.block, j.junction, j.dropped_energy
            );
        }
        return;
    }
    println!("time,step,drive_ratio,kinetic_energy,ruptures,pinned_fraction");
    for g in &run.global {
        println!(
            "{:.9e},{},{:.9e},{:.6e},{},{:.9}",
            g.time, g.step, g.drive_ratio, g.kinetic_energy, g.ruptures, g.pinned_fraction
        );
    }
}
