//! CPU seconds per thread of this process over a span, by thread name: which
//! host thread (the runner, the file's writing thread, the driver's) a
//! timed span keeps busy. Linux only (/proc); elsewhere it reports nothing.
//! A thread that ends in the span (the file's writer, at the run's end) is
//! sampled every `EVERY` while the span lasts, so its last `EVERY` at most
//! is missed. The sampler reads every thread's /proc entry each time: with
//! a sweep's 256 runner threads, every 20 ms cost it 0.57 CPU seconds per
//! wall second on the H200 machine (session 16), hence 100 ms.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

const EVERY: Duration = Duration::from_millis(100);

/// (name, CPU seconds so far) of each live thread, by thread id. The main
/// thread is named "main" (threads a driver starts often inherit its name).
fn threads_now() -> BTreeMap<u32, (String, f64)> {
    let mut out = BTreeMap::new();
    let pid = std::process::id();
    // SAFETY: sysconf has no preconditions.
    let ticks = unsafe { libc::sysconf(libc::_SC_CLK_TCK) }.max(1) as f64;
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return out;
    };
    for entry in dir.flatten() {
        let Ok(tid) = entry.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(entry.path().join("stat")) else {
            continue;
        };
        // "tid (comm) state ..." — comm may hold spaces or parentheses.
        let (Some(open), Some(close)) = (stat.find('('), stat.rfind(')')) else {
            continue;
        };
        let fields: Vec<&str> = stat[close + 1..].split_whitespace().collect();
        // After comm: state is field 3, utime 14, stime 15 (1-based).
        let (Some(u), Some(s)) = (fields.get(11), fields.get(12)) else {
            continue;
        };
        let cpu = (u.parse::<f64>().unwrap_or(0.0) + s.parse::<f64>().unwrap_or(0.0)) / ticks;
        let name = if tid == pid {
            "main".to_string()
        } else {
            stat[open + 1..close].to_string()
        };
        out.insert(tid, (name, cpu));
    }
    out
}

/// Samples every thread's CPU time from `start` until `finish`.
pub struct ThreadCpu {
    before: BTreeMap<u32, (String, f64)>,
    last: Arc<Mutex<BTreeMap<u32, (String, f64)>>>,
    done: Arc<AtomicBool>,
    sampler: Option<JoinHandle<()>>,
}

impl ThreadCpu {
    pub fn start() -> Self {
        let before = threads_now();
        let last = Arc::new(Mutex::new(before.clone()));
        let done = Arc::new(AtomicBool::new(false));
        let sampler = {
            let (last, done) = (last.clone(), done.clone());
            std::thread::Builder::new()
                .name("bench-cpu-sampler".into())
                .spawn(move || {
                    while !done.load(Ordering::Relaxed) {
                        let now = threads_now();
                        let mut last = last.lock().unwrap();
                        for (tid, seen) in now {
                            last.insert(tid, seen);
                        }
                        drop(last);
                        std::thread::sleep(EVERY);
                    }
                })
                .ok()
        };
        ThreadCpu {
            before,
            last,
            done,
            sampler,
        }
    }

    /// CPU seconds in the span by thread name (threads of one name summed),
    /// largest first; the sampler itself left out.
    pub fn finish(mut self) -> Vec<(String, f64)> {
        let now = threads_now();
        self.done.store(true, Ordering::Relaxed);
        if let Some(s) = self.sampler.take() {
            let _ = s.join();
        }
        let mut last = self.last.lock().unwrap().clone();
        for (tid, seen) in now {
            last.insert(tid, seen);
        }
        let mut by_name: BTreeMap<String, f64> = BTreeMap::new();
        for (tid, (name, cpu)) in last {
            if name == "bench-cpu-sampler" {
                continue;
            }
            let start = self.before.get(&tid).map_or(0.0, |b| b.1);
            *by_name.entry(name).or_default() += (cpu - start).max(0.0);
        }
        let mut out: Vec<(String, f64)> = by_name.into_iter().collect();
        out.sort_by(|a, b| b.1.total_cmp(&a.1));
        out
    }
}

/// "main 0.61, slipfront-mcap 0.30, ..." in CPU seconds per wall second,
/// threads under 0.02 left out.
pub fn per_wall(threads: &[(String, f64)], wall: f64) -> String {
    let shown: Vec<String> = threads
        .iter()
        .filter(|(_, cpu)| cpu / wall >= 0.02)
        .map(|(name, cpu)| format!("{name} {:.2}", cpu / wall))
        .collect();
    if shown.is_empty() {
        "none over 0.02".into()
    } else {
        shown.join(", ")
    }
}
