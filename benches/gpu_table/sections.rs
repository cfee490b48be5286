//! Which sections run, and each one's wall time.

use std::time::Instant;

/// Which sections to run (`SLIPFRONT_GPU_TABLE_SECTIONS=1,3,6`; all by
/// default), so that a short loan of a GPU can run the table in parts;
/// each section's own wall time is printed after it.
pub struct Sections(Vec<u32>);

/// Prints a section's wall time when dropped.
pub struct SectionTimer(u32, Instant);

impl Drop for SectionTimer {
    fn drop(&mut self) {
        println!(
            "\n(section {} took {:.1} s of wall time)\n",
            self.0,
            self.1.elapsed().as_secs_f64()
        );
    }
}

impl Sections {
    pub fn from_env() -> Self {
        let all = (1..=12).collect();
        match std::env::var("SLIPFRONT_GPU_TABLE_SECTIONS") {
            Ok(list) => Sections(
                list.split(',')
                    .map(|s| match s.trim().parse() {
                        Ok(n @ 1..=12) => n,
                        _ => {
                            panic!("SLIPFRONT_GPU_TABLE_SECTIONS: `{s}` is not a section (1 to 12)")
                        }
                    })
                    .collect(),
            ),
            Err(_) => Sections(all),
        }
    }

    pub fn start(&self, n: u32) -> Option<SectionTimer> {
        self.0.contains(&n).then(|| SectionTimer(n, Instant::now()))
    }
}
