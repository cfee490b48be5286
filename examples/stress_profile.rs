//! τ/p along the interface at the last `/interface` record before a time:
//! `cargo run --release --example stress_profile -- RUN.mcap TIME`.
//! Shows how far the local stress ratio is from the slider average F/F_N
//! (the side spring loads the trailing edge first).

use slipfront::io::output::reader::RunFile;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let (path, time) = match args.as_slice() {
        [_, p, t] => (p, t.parse::<f64>()?),
        _ => anyhow::bail!("usage: stress_profile RUN.mcap TIME"),
    };
    let run = RunFile::read(std::path::Path::new(path))?;
    let rec = run
        .interface
        .iter()
        .rev()
        .find(|m| m.time < time)
        .ok_or_else(|| anyhow::anyhow!("no /interface record before t = {time}"))?;
    let ratio: Vec<f64> = rec
        .shear_stress
        .iter()
        .zip(&rec.normal_stress)
        .map(|(t, p)| t / p)
        .collect();
    let shear: f64 = rec.shear_stress.iter().sum();
    let normal: f64 = rec.normal_stress.iter().sum();
    println!(
        "t = {:.6e} s, F/F_N = {:.4}, interface Στ/Σp = {:.4}",
        rec.time,
        run.drive_ratio_at(rec.time),
        shear / normal
    );
    println!("block  x (m)       tau/p");
    let spacing = run.spacing();
    for (ix, r) in ratio.iter().enumerate() {
        println!("{ix:<6} {:<11.4e} {r:.4}", ix as f64 * spacing);
    }
    Ok(())
}
