//! Prints the `/global` series of a run file as CSV (time, step, drive
//! ratio, kinetic energy, ruptures, pinned fraction), for quick looks.
fn main() {
    let path = std::env::args()
        .nth(1)
        .expect("usage: dump_global RUN.mcap");
    let run = slipfront::output::reader::RunFile::read(std::path::Path::new(&path))
        .unwrap_or_else(|e| panic!("{e}"));
    println!("time,step,drive_ratio,kinetic_energy,ruptures,pinned_fraction");
    for g in &run.global {
        println!(
            "{:.9e},{},{:.9e},{:.6e},{},{:.9}",
            g.time, g.step, g.drive_ratio, g.kinetic_energy, g.ruptures, g.pinned_fraction
        );
    }
}
